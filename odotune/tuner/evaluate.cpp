#include <odotune/tuner/evaluate.h>

#include <algorithm>
#include <exception>
#include <limits>

namespace odotune::tuner {

std::vector<double> evaluate_all(ProblemRef problem, const std::vector<std::vector<double>>& points,
                                 const std::atomic<bool>* stop) {
  // Groups of batch_size() points per call (one point each for a problem
  // without fitness_batch); the values do not depend on the grouping.
  const std::size_t group = static_cast<std::size_t>(std::max(1, problem.batch_size()));
  const long groups = static_cast<long>((points.size() + group - 1) / group);
  std::vector<double> out(points.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<std::exception_ptr> errors(points.size());
#pragma omp parallel for schedule(dynamic)
  for (long g = 0; g < groups; ++g) {
    if (stop != nullptr && stop->load()) continue;
    const std::size_t a = static_cast<std::size_t>(g) * group, b = std::min(points.size(), a + group);
    try {
      std::vector<double> xs;
      for (std::size_t i = a; i < b; ++i) xs.insert(xs.end(), points[i].begin(), points[i].end());
      problem.fitness_batch(xs, std::span<double>(out).subspan(a, b - a));
    } catch (...) {
      errors[a] = std::current_exception();
    }
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  return out;
}

}  // namespace odotune::tuner

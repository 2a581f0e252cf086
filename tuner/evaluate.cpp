#include "tuner/evaluate.h"

#include <exception>
#include <limits>

namespace odotune::tuner {

std::vector<double> evaluate_all(ProblemRef problem, const std::vector<std::vector<double>>& points,
                                 const std::atomic<bool>* stop) {
  const long n = static_cast<long>(points.size());
  std::vector<double> out(points.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<std::exception_ptr> errors(points.size());
#pragma omp parallel for schedule(dynamic)
  for (long i = 0; i < n; ++i) {
    if (stop != nullptr && stop->load()) continue;
    try {
      out[static_cast<std::size_t>(i)] = problem.fitness(points[static_cast<std::size_t>(i)]);
    } catch (...) {
      errors[static_cast<std::size_t>(i)] = std::current_exception();
    }
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  return out;
}

}  // namespace odotune::tuner

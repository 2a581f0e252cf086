#include <odotune/jobs/rl_search.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include <fmt/format.h>

#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>
#include <odotune/tuner/evaluate.h>

namespace odotune::jobs {
namespace {

using core::seconds_since;

// The block (0 position … 4 acceleration) of each parameter of the space, or
// −1 for a parameter on an input's covariance.
std::vector<int> blocks_of(const objectives::RlObjective& objective) {
  std::vector<int> out;
  for (const objectives::ParamSpec& p : objective.space().params()) {
    const std::vector<int> members = objectives::rl_noise_members(p.name, false);
    out.push_back(members.empty() ? -1 : members.front() / 3);
  }
  return out;
}

// The data fitness, for the profile (the prior is not the recording's).
struct DataFitness {
  const objectives::RlObjective* objective;
  double fitness(std::span<const double> x) const { return objective->data_fitness(x); }
  void fitness_batch(std::span<const double> xs, std::span<double> out) const {
    objective->data_fitness_batch(xs, out);
  }
  int batch_size() const { return objective->batch_size(); }
  tuner::Bounds bounds() const {
    auto [lo, hi] = objective->bounds();
    return {lo, hi};
  }
};

void report(const SolverSettings& s, long done, long total) {
  if (s.progress) s.progress(done, total);
}

}  // namespace

namespace {

// A point's profile, then the reset of what the recording did not determine:
// r.x and r.fitness (the data fitness at r.x) in, the reset point out.
struct Profiled {
  std::vector<double> x;
  double fitness = 0.0;
  std::vector<RlParamProfile> profiles;
  long evaluations = 0;
};

void profile_and_reset(const objectives::RlObjective& objective, const objectives::RlSearchOptions& options,
                       const SolverSettings& settings, Profiled& r) {
  // Named, not a structured binding: the lambda below captures them, which
  // clang (and so clang-tidy) before 16 cannot compile.
  const auto box = objective.bounds();
  const std::vector<double>& lo = box.first;
  const std::vector<double>& hi = box.second;
  const std::size_t n = lo.size();
  const DataFitness data{&objective};
  std::vector<std::vector<double>> points;
  std::vector<std::vector<double>> levels(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (double v = lo[i]; v < hi[i] + 1e-9; v += options.profile_step_decades) levels[i].push_back(v);
    if (std::find(levels[i].begin(), levels[i].end(), 0.0) == levels[i].end() && lo[i] < 0.0 && hi[i] > 0.0)
      levels[i].push_back(0.0);
    std::sort(levels[i].begin(), levels[i].end());
    for (double v : levels[i]) {
      std::vector<double> x = r.x;
      x[i] = v;
      points.push_back(std::move(x));
    }
  }
  const std::vector<double> f = tuner::evaluate_all(data, points, settings.stop);
  r.evaluations += static_cast<long>(points.size());
  const double best = r.fitness, bound = best * (1.0 + options.tolerance);
  std::size_t k = 0;
  r.profiles.assign(n, {});
  for (std::size_t i = 0; i < n; ++i) {
    const std::vector<double>& v = levels[i];
    const std::vector<double> fi(f.begin() + static_cast<std::ptrdiff_t>(k),
                                 f.begin() + static_cast<std::ptrdiff_t>(k + v.size()));
    k += v.size();
    // Walk out from the tuned value while the fitness stays within the bound;
    // the range's ends are where a straight line between grid points crosses it.
    const double xi = r.x[i];
    auto edge = [&](int dir) {
      double last_x = xi, last_f = best;
      for (std::size_t j = 0; j < v.size(); ++j) {
        const std::size_t m = dir > 0 ? j : v.size() - 1 - j;
        if ((dir > 0 && v[m] <= xi) || (dir < 0 && v[m] >= xi)) continue;
        if (!(fi[m] <= bound)) {
          const double t = std::isfinite(fi[m]) ? (bound - last_f) / (fi[m] - last_f) : 0.0;
          return last_x + std::clamp(t, 0.0, 1.0) * (v[m] - last_x);
        }
        last_x = v[m];
        last_f = std::max(fi[m], best);
      }
      return dir > 0 ? hi[i] : lo[i];
    };
    RlParamProfile& p = r.profiles[i];
    p.lo = std::pow(10.0, edge(-1));
    p.hi = std::pow(10.0, edge(+1));
    const auto at0 = std::find(v.begin(), v.end(), 0.0);
    p.at_file_value = at0 != v.end() ? fi[static_cast<std::size_t>(at0 - v.begin())] : best;
    p.determined = !(p.lo <= 1.0 && 1.0 <= p.hi);
  }
  // Reset every undetermined parameter; while that costs more than the
  // tolerance, keep tuned the one whose own reset costs most.
  std::vector<std::size_t> reset;
  for (std::size_t i = 0; i < n; ++i)
    if (!r.profiles[i].determined) reset.push_back(i);
  std::sort(reset.begin(), reset.end(), [&](std::size_t a, std::size_t b) {
    return r.profiles[a].at_file_value < r.profiles[b].at_file_value;
  });
  while (!reset.empty()) {
    std::vector<double> x = r.x;
    for (std::size_t i : reset) x[i] = 0.0;
    const double fx = objective.data_fitness(x);
    ++r.evaluations;
    if (fx <= bound) {
      r.x = x;
      r.fitness = fx;
      break;
    }
    r.profiles[reset.back()].determined = true;
    reset.pop_back();
  }
}

}  // namespace

namespace {

// The grid's best profiled and reset (when the options ask for a profile).
void profile_grid(const objectives::RlObjective& objective, const objectives::RlSearchOptions& options,
                  const SolverSettings& settings, RlGridResult& r) {
  if (!options.profile || (settings.stop && settings.stop->load())) return;
  Profiled p{r.x, objective.data_fitness(r.x), {}, 1};
  profile_and_reset(objective, options, settings, p);
  r.x = p.x;
  r.fitness = objective.fitness(p.x);
  r.profiles = p.profiles;
  r.evaluations += p.evaluations + 1;
}

// The refinement's problem: the free parameters of `base`, in their box.
struct Subset {
  const objectives::RlObjective* objective;
  std::vector<double> base;
  std::vector<std::size_t> free;
  std::vector<double> lo, hi;
  std::vector<double> full(std::span<const double> x) const {
    std::vector<double> out = base;
    for (std::size_t k = 0; k < free.size(); ++k) out[free[k]] = x[k];
    return out;
  }
  double fitness(std::span<const double> x) const { return objective->fitness(full(x)); }
  void fitness_batch(std::span<const double> xs, std::span<double> out) const {
    std::vector<double> all;
    for (std::size_t k = 0; k < out.size(); ++k) {
      const std::vector<double> x = full(xs.subspan(k * free.size(), free.size()));
      all.insert(all.end(), x.begin(), x.end());
    }
    objective->fitness_batch(all, out);
  }
  int batch_size() const { return objective->batch_size(); }
  tuner::Bounds bounds() const { return {lo, hi}; }
};

}  // namespace

long rl_grid_points(const objectives::RlObjective& objective, const objectives::RlSearchOptions& options) {
  if (options.grid_levels.empty()) return 1;
  const std::vector<int> block = blocks_of(objective);
  const int nb = 1 + *std::max_element(block.begin(), block.end());
  long count = 1;
  for (int b = 0; b < nb; ++b) count *= static_cast<long>(options.grid_levels.size());
  return count;
}

RlGridResult rl_grid_stage(const objectives::RlObjective& objective, const objectives::RlSearchOptions& options,
                           const SolverSettings& settings) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto [lo, hi] = objective.bounds();
  const std::vector<int> block = blocks_of(objective);
  RlGridResult r;
  r.x.assign(lo.size(), 0.0);
  if (options.grid_levels.empty()) {
    r.fitness = objective.fitness(r.x);
    r.points = 1;
    r.evaluations = 1;
    profile_grid(objective, options, settings, r);
    r.seconds = seconds_since(t0);
    return r;
  }
  const int nb = 1 + *std::max_element(block.begin(), block.end());
  const auto nl = static_cast<long>(options.grid_levels.size());
  const long count = rl_grid_points(objective, options);
  std::vector<std::vector<double>> points;
  for (long k = 0; k < count; ++k) {
    std::vector<double> x(lo.size(), 0.0);
    long code = k;
    std::vector<double> level(static_cast<std::size_t>(nb));
    for (int b = 0; b < nb; ++b, code /= nl)
      level[static_cast<std::size_t>(b)] = options.grid_levels[code % nl];
    for (std::size_t i = 0; i < x.size(); ++i)
      if (block[i] >= 0) x[i] = std::clamp(level[static_cast<std::size_t>(block[i])], lo[i], hi[i]);
    points.push_back(std::move(x));
  }
  const BoxProblem<objectives::RlObjective> problem{&objective};
  const std::vector<double> f = tuner::evaluate_all(problem, points, settings.stop);
  // The lowest; on a tie, the first in the grid's order.
  std::size_t best = 0;
  for (std::size_t k = 1; k < f.size(); ++k)
    if (f[k] < f[best]) best = k;
  r.x = points[best];
  r.fitness = f[best];
  r.points = count;
  r.evaluations = count;
  report(settings, count, count);
  profile_grid(objective, options, settings, r);
  r.seconds = seconds_since(t0);
  return r;
}

RlStartResult rl_refine_and_profile(const objectives::RlObjective& objective, const RlGridResult& grid,
                                    const objectives::RlSearchOptions& options,
                                    const SolverSettings& settings) {
  const auto t0 = std::chrono::steady_clock::now();
  RlStartResult r;
  r.seed = settings.seed;
  r.x = grid.x;
  r.profiles = grid.profiles;
  const auto [lo, hi] = objective.bounds();
  Subset sub{&objective, grid.x, {}, {}, {}};
  for (std::size_t i = 0; i < lo.size(); ++i) {
    if (!grid.profiles.empty() && !grid.profiles[i].determined) continue;
    sub.free.push_back(i);
    sub.lo.push_back(std::max(lo[i], grid.x[i] - options.refine_decades));
    sub.hi.push_back(std::min(hi[i], grid.x[i] + options.refine_decades));
  }
  r.refined_fitness = r.fitness = objective.data_fitness(r.x);
  ++r.evaluations;
  if (options.refine_decades > 0.0 && !sub.free.empty()) {
    std::vector<double> x0;
    for (std::size_t i : sub.free) x0.push_back(grid.x[i]);
    r.refinement = run_solver(sub, settings, x0);
    r.evaluations += r.refinement.evaluations;
    // The grid's point stays the answer unless the refinement beat it.
    if (r.refinement.best_fitness < grid.fitness) {
      for (std::size_t k = 0; k < sub.free.size(); ++k) r.x[sub.free[k]] = r.refinement.best_x[k];
      Profiled p{r.x, objective.data_fitness(r.x), {}, 1};
      r.refined_fitness = p.fitness;
      if (options.profile && !(settings.stop && settings.stop->load()))
        profile_and_reset(objective, options, settings, p);
      r.x = p.x;
      r.fitness = p.fitness;
      if (!p.profiles.empty()) r.profiles = p.profiles;
      r.evaluations += p.evaluations;
    }
  }
  r.seconds = seconds_since(t0);
  return r;
}

}  // namespace odotune::jobs

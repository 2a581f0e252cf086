#include <odotune/tuner/pso.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <span>
#include <sstream>
#include <utility>
#include <vector>

#include <odotune/core/counter_rng.h>
#include <odotune/core/why.h>
#include <odotune/tuner/solver_run.h>

namespace odotune::tuner {
namespace {

using detail::kInf;
using detail::str;
using detail::what_of;

// Streams of the counter-based generator (the last key word).
enum Stream : std::uint64_t { kInitPosition = 0, kInitVelocity = 1, kR1 = 2, kR2 = 3 };

// Non-finite values become +inf so that a plain `<` never prefers them and
// NaN never poisons a comparison.
double sanitize(double f) {
  return std::isfinite(f) ? f : kInf;  // NOLINT(bugprone-narrowing-conversions): false positive on +inf
}

// The swarm's state, row-major [particle][dimension], and its best.
struct Swarm {
  Swarm(int particles, std::size_t dimension)
      : dim(dimension),
        x(static_cast<std::size_t>(particles) * dimension),
        v(static_cast<std::size_t>(particles) * dimension),
        pbest_x(static_cast<std::size_t>(particles) * dimension),
        fit(static_cast<std::size_t>(particles)),
        pbest_f(static_cast<std::size_t>(particles), kInf),
        errors(static_cast<std::size_t>(particles)),
        gbest_x(dimension) {}
  std::size_t dim;
  std::vector<double> x, v, pbest_x;
  std::vector<double> fit, pbest_f;
  std::vector<std::exception_ptr> errors;
  std::vector<double> gbest_x;
  double gbest_f = kInf;
};

// What moving a particle reads: the box, its widths and velocity limits, the
// options and the problem.
struct Motion {
  const Bounds& box;
  const std::vector<double>& width;
  const std::vector<double>& vmax;
  const PsoOptions& options;
  ProblemRef problem;

  double uniform(int iteration, int particle, std::size_t d, Stream stream) const {
    return core::counter_uniform01(options.seed, static_cast<std::uint64_t>(iteration),
                                   static_cast<std::uint64_t>(particle), d, stream);
  }
};

// Moves particle i for iteration t (t >= 1); or, for t == 0, initialises it.
// Runs inside the parallel loop: it touches only particle i's rows and reads
// gbest_x, which is not written during the loop.
inline void move_particle(Swarm& s, const Motion& m, int t, int i) {
  const std::size_t dim = s.dim;
  const Bounds& box = m.box;
  const PsoOptions& options = m.options;
  double* xi = &s.x[static_cast<std::size_t>(i) * dim];
  double* vi = &s.v[static_cast<std::size_t>(i) * dim];
  const double* pi = &s.pbest_x[static_cast<std::size_t>(i) * dim];
  for (std::size_t d = 0; d < dim; ++d) {
    if (t == 0) {
      xi[d] = box.lower[d] + m.uniform(0, i, d, kInitPosition) * m.width[d];
      xi[d] = std::min(xi[d], box.upper[d]);
      vi[d] = (2 * m.uniform(0, i, d, kInitVelocity) - 1) * options.initial_velocity_fraction * m.width[d];
      continue;
    }
    const double r1 = m.uniform(t, i, d, kR1);
    const double r2 = m.uniform(t, i, d, kR2);
    double vel = options.inertia * vi[d] + options.cognitive * r1 * (pi[d] - xi[d]) +
                 options.social * r2 * (s.gbest_x[d] - xi[d]);
    vel = std::clamp(vel, -m.vmax[d], m.vmax[d]);
    double pos = xi[d] + vel;
    if (pos < box.lower[d]) {
      pos = box.lower[d];
      vel = 0;
    } else if (pos > box.upper[d]) {
      pos = box.upper[d];
      vel = 0;
    }
    xi[d] = pos;
    vi[d] = vel;
  }
}

// Moves and evaluates particles [first, last): one by one, or in one
// fitness_batch call when the problem has one. A call that throws marks each
// of its particles as failed.
inline void step_particles(Swarm& s, const Motion& m, int t, int first, int last) {
  const std::size_t dim = s.dim;
  for (int i = first; i < last; ++i) move_particle(s, m, t, i);
  const auto a = static_cast<std::size_t>(first), b = static_cast<std::size_t>(last);
  try {
    if (m.problem.batch_size() > 1) {
      const std::span<double> out(&s.fit[a], b - a);
      m.problem.fitness_batch(std::span<const double>(&s.x[a * dim], (b - a) * dim), out);
      for (double& f : out) f = sanitize(f);
    } else {
      for (std::size_t i = a; i < b; ++i) {
        s.fit[i] = sanitize(m.problem.fitness(std::span<const double>(&s.x[i * dim], dim)));
      }
    }
  } catch (...) {
    for (std::size_t i = a; i < b; ++i) {
      s.fit[i] = kInf;
      s.errors[i] = std::current_exception();
    }
  }
}

// Sequential best update in particle index order; strict `<` keeps the
// earlier (lower-index / older) record on ties. Returns the first particle
// whose evaluation threw (its bests not updated), or -1.
int update_bests(Swarm& s, int n, int t) {
  const std::size_t dim = s.dim;
  for (int i = 0; i < n; ++i) {
    const std::size_t ui = static_cast<std::size_t>(i);
    if (s.errors[ui]) return i;
    const double* xi = &s.x[ui * dim];
    if (t == 0 || s.fit[ui] < s.pbest_f[ui]) {
      s.pbest_f[ui] = s.fit[ui];
      std::copy(xi, xi + dim, s.pbest_x.begin() + static_cast<std::ptrdiff_t>(ui * dim));
    }
    if ((t == 0 && i == 0) || s.fit[ui] < s.gbest_f) {
      s.gbest_f = s.fit[ui];
      std::copy(xi, xi + dim, s.gbest_x.begin());
    }
  }
  return -1;
}

}  // namespace

bool PsoOptions::IsValid(std::string* why) const {
  if (particles < 1)
    return core::invalid(why, "pso: particles = " + std::to_string(particles) + ", expected >= 1");
  if (iterations < 0)
    return core::invalid(why, "pso: iterations = " + std::to_string(iterations) + ", expected >= 0");
  if (!(std::isfinite(inertia) && inertia >= 0 && inertia < 1))
    return core::invalid(why, "pso: inertia = " + str(inertia) + ", expected a value in [0, 1)");
  if (!(std::isfinite(cognitive) && cognitive >= 0))
    return core::invalid(why, "pso: cognitive = " + str(cognitive) + ", expected a finite value >= 0");
  if (!(std::isfinite(social) && social >= 0))
    return core::invalid(why, "pso: social = " + str(social) + ", expected a finite value >= 0");
  if (!(initial_velocity_fraction >= 0 && initial_velocity_fraction <= 1))
    return core::invalid(why, "pso: initial_velocity_fraction = " + str(initial_velocity_fraction) +
                                  ", expected a value in [0, 1]");
  if (!(max_velocity_fraction > 0 && max_velocity_fraction <= 1))
    return core::invalid(why, "pso: max_velocity_fraction = " + str(max_velocity_fraction) +
                                  ", expected a value in (0, 1]");
  return true;
}

Summary pso_minimize(ProblemRef problem, const PsoOptions& options) {
  detail::SolverRun solver_run;
  Summary& summary = solver_run.summary;
  auto finish = [&solver_run](Termination t, std::string message = {}) {
    return solver_run.finish(t, std::move(message));
  };
  Bounds box;
  if (auto failure = solver_run.start(options, problem, &box)) return finish(Termination::failure, *failure);

  const int n = options.particles;
  const std::size_t dim = box.dimension();
  const long total = options.evaluation_budget();
  std::vector<double> width(dim), vmax(dim);
  for (std::size_t d = 0; d < dim; ++d) {
    width[d] = box.upper[d] - box.lower[d];
    vmax[d] = options.max_velocity_fraction * width[d];
  }
  Swarm s(n, dim);
  const Motion m{box, width, vmax, options, problem};
  // The particles evaluated together: batch_size() of them for a batch problem.
  const int group = std::min(n, problem.batch_size());
  const int groups = (n + group - 1) / group;

  for (int t = 0; t <= options.iterations; ++t) {
    if (t > 0 && options.stop != nullptr && options.stop->load()) return finish(Termination::stopped);

#pragma omp parallel for schedule(dynamic)
    for (int g = 0; g < groups; ++g) step_particles(s, m, t, g * group, std::min(n, (g + 1) * group));

    summary.evaluations += n;
    summary.iterations = t;
    if (const int bad = update_bests(s, n, t); bad >= 0)
      return finish(Termination::failure, what_of(s.errors[static_cast<std::size_t>(bad)]));
    summary.best_x = s.gbest_x;
    summary.best_fitness = s.gbest_f;
    summary.log.push_back({t, summary.evaluations, s.gbest_f});
    if (options.progress) {
      try {
        options.progress(summary.evaluations, total);
      } catch (...) {
        return finish(Termination::failure, "progress callback threw: " + what_of(std::current_exception()));
      }
    }
  }
  return finish(Termination::max_iterations);
}

}  // namespace odotune::tuner

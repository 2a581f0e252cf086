#include "tuner/pso.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include "core/counter_rng.h"
#include "tuner/solver_run.h"

namespace odotune::tuner {
namespace {

using detail::kInf;
using detail::str;
using detail::what_of;

// Streams of the counter-based generator (the last key word).
enum Stream : std::uint64_t { kInitPosition = 0, kInitVelocity = 1, kR1 = 2, kR2 = 3 };

// Non-finite values become +inf so that a plain `<` never prefers them and
// NaN never poisons a comparison.
double sanitize(double f) { return std::isfinite(f) ? f : kInf; }

}  // namespace

bool PsoOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& message) {
    if (why != nullptr) *why = "pso: " + message;
    return false;
  };
  if (particles < 1) return fail("particles = " + std::to_string(particles) + ", expected >= 1");
  if (iterations < 0) return fail("iterations = " + std::to_string(iterations) + ", expected >= 0");
  if (!(std::isfinite(inertia) && inertia >= 0 && inertia < 1))
    return fail("inertia = " + str(inertia) + ", expected a value in [0, 1)");
  if (!(std::isfinite(cognitive) && cognitive >= 0))
    return fail("cognitive = " + str(cognitive) + ", expected a finite value >= 0");
  if (!(std::isfinite(social) && social >= 0))
    return fail("social = " + str(social) + ", expected a finite value >= 0");
  if (!(initial_velocity_fraction >= 0 && initial_velocity_fraction <= 1))
    return fail("initial_velocity_fraction = " + str(initial_velocity_fraction) +
                ", expected a value in [0, 1]");
  if (!(max_velocity_fraction > 0 && max_velocity_fraction <= 1))
    return fail("max_velocity_fraction = " + str(max_velocity_fraction) + ", expected a value in (0, 1]");
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
  const std::uint64_t seed = options.seed;
  const long total = options.evaluation_budget();
  std::vector<double> width(dim), vmax(dim);
  for (std::size_t d = 0; d < dim; ++d) {
    width[d] = box.upper[d] - box.lower[d];
    vmax[d] = options.max_velocity_fraction * width[d];
  }

  // Swarm state, row-major [particle][dimension].
  const std::size_t cells = static_cast<std::size_t>(n) * dim;
  std::vector<double> x(cells), v(cells), pbest_x(cells);
  std::vector<double> fit(static_cast<std::size_t>(n)), pbest_f(static_cast<std::size_t>(n), kInf);
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(n));
  std::vector<double> gbest_x(dim);
  double gbest_f = kInf;

  auto uniform = [seed](int iteration, int particle, std::size_t d, Stream stream) {
    return counter_uniform01(seed, static_cast<std::uint64_t>(iteration), static_cast<std::uint64_t>(particle),
                             d, stream);
  };

  // Moves particle i for iteration t (t >= 1) and evaluates it; or, for
  // t == 0, initialises and evaluates it. Runs inside the parallel loop: it
  // touches only particle i's rows and reads gbest_x, which is not written
  // during the loop.
  auto step_particle = [&](int t, int i) {
    double* xi = &x[static_cast<std::size_t>(i) * dim];
    double* vi = &v[static_cast<std::size_t>(i) * dim];
    const double* pi = &pbest_x[static_cast<std::size_t>(i) * dim];
    for (std::size_t d = 0; d < dim; ++d) {
      if (t == 0) {
        xi[d] = box.lower[d] + uniform(0, i, d, kInitPosition) * width[d];
        xi[d] = std::min(xi[d], box.upper[d]);
        vi[d] = (2 * uniform(0, i, d, kInitVelocity) - 1) * options.initial_velocity_fraction * width[d];
        continue;
      }
      const double r1 = uniform(t, i, d, kR1);
      const double r2 = uniform(t, i, d, kR2);
      double vel = options.inertia * vi[d] + options.cognitive * r1 * (pi[d] - xi[d]) +
                   options.social * r2 * (gbest_x[d] - xi[d]);
      vel = std::clamp(vel, -vmax[d], vmax[d]);
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
    try {
      fit[static_cast<std::size_t>(i)] = sanitize(problem.fitness(std::span<const double>(xi, dim)));
    } catch (...) {
      fit[static_cast<std::size_t>(i)] = kInf;
      errors[static_cast<std::size_t>(i)] = std::current_exception();
    }
  };

  for (int t = 0; t <= options.iterations; ++t) {
    if (t > 0 && options.stop != nullptr && options.stop->load()) return finish(Termination::stopped);

#pragma omp parallel for schedule(dynamic)
    for (int i = 0; i < n; ++i) step_particle(t, i);

    summary.evaluations += n;
    summary.iterations = t;
    // Sequential best update in particle index order; strict `<` keeps the
    // earlier (lower-index / older) record on ties.
    for (int i = 0; i < n; ++i) {
      const std::size_t ui = static_cast<std::size_t>(i);
      if (errors[ui]) return finish(Termination::failure, what_of(errors[ui]));
      const double* xi = &x[ui * dim];
      if (t == 0 || fit[ui] < pbest_f[ui]) {
        pbest_f[ui] = fit[ui];
        std::copy(xi, xi + dim, pbest_x.begin() + static_cast<std::ptrdiff_t>(ui * dim));
      }
      if ((t == 0 && i == 0) || fit[ui] < gbest_f) {
        gbest_f = fit[ui];
        std::copy(xi, xi + dim, gbest_x.begin());
      }
    }
    summary.best_x = gbest_x;
    summary.best_fitness = gbest_f;
    summary.log.push_back({t, summary.evaluations, gbest_f});
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

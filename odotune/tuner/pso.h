// Global-best particle swarm optimisation (PSO) over a finite box.
//
// Algorithm (synchronous gbest PSO with constriction):
//   Iteration 0: every particle i gets a position x_i uniform in the box and a
//     velocity v_i uniform in ±initial_velocity_fraction·(upper−lower); all
//     particles are evaluated; personal bests p_i = x_i; the global best g is
//     the best p_i.
//   Iterations t = 1..iterations, per particle i and dimension d:
//     v ← w·v + c1·r1·(p_i − x) + c2·r2·(g − x),   r1, r2 ~ U[0,1) fresh per (t,i,d)
//     v ← clamp(v, ±max_velocity_fraction·(upper−lower))
//     x ← x + v; if x leaves the box it is clamped onto the bound and that
//       velocity component is set to 0 ("absorbing walls", J. Robinson &
//       Y. Rahmat-Samii, "Particle swarm optimization in electromagnetics",
//       IEEE Trans. Antennas Propag. 52(2), 2004). Chosen because every
//       evaluated point then lies inside the box, as the Problem contract
//       promises, and a particle is not thrown back across the box.
//     Then all particles are evaluated, and p_i and g are updated.
//   g is the gbest of the previous iteration for the whole update (synchronous).
//
// Defaults w = 0.7298, c1 = c2 = 1.49618 are the Clerc–Kennedy constriction
// coefficients for φ = 4.1 (χ = 0.7298, χ·φ/2 = 1.49618): M. Clerc &
// J. Kennedy, "The particle swarm — explosion, stability, and convergence in
// a multidimensional complex space", IEEE Trans. Evol. Comput. 6(1):58–73,
// 2002.
//
// Parallelism and determinism: the fitness evaluations (and the position
// updates) of one iteration run in an OpenMP `parallel for schedule(dynamic)`;
// personal and global bests are then updated sequentially in particle index
// order, and on equal fitness the earlier record is kept (so ties keep the
// lower particle index). r1, r2 and the initial draws come from a
// counter-based hash of (seed, iteration, particle, dimension, stream)
// (counter_rng.h), so the same seed gives a bit-identical Summary (best_x,
// best_fitness, log) for any number of OpenMP threads.
//
// Evaluation count: exactly particles × (iterations + 1) when the run is not
// stopped; a run stopped before iteration t (t ≥ 1) made particles × t.
//
// Non-finite fitness values are treated as worse than every finite value and
// never become a personal or global best (objectives should still return a
// finite penalty, see problem.h). If no finite value was ever seen,
// best_fitness is +infinity and best_x is particle 0's initial position.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include <odotune/tuner/problem.h>
#include <odotune/tuner/summary.h>

namespace odotune::tuner {

struct PsoOptions {
  int particles = 50;                      // swarm size, >= 1
  int iterations = 150;                    // iterations after the initial swarm, >= 0
  double inertia = 0.7298;                 // w (constriction χ), in [0, 1)
  double cognitive = 1.49618;              // c1, >= 0, finite
  double social = 1.49618;                 // c2, >= 0, finite
  double initial_velocity_fraction = 0.1;  // v0: initial |v_d| <= v0·width_d, in [0, 1]
  double max_velocity_fraction = 0.5;      // |v_d| <= vmax·width_d after each update, in (0, 1]

  std::uint64_t seed = 0;  // explicit seed; the same seed gives the same run
  // Optional. Called from the calling thread only (never inside the parallel
  // region) after the initial swarm and after every iteration, with
  // (evaluations done, particles × (iterations + 1)).
  std::function<void(long done, long total)> progress;
  // Optional. Polled by the calling thread before each iteration t >= 1 (the
  // initial swarm is always evaluated); when it reads true the run ends with
  // Termination::stopped. Set it from a signal handler for Ctrl-C.
  const std::atomic<bool>* stop = nullptr;

  // True if usable; otherwise false and *why (if given) names the bad field
  // and value, e.g. "pso: particles = 0, expected >= 1".
  bool IsValid(std::string* why) const;

  // particles × (iterations + 1), the evaluations of an unstopped run.
  long evaluation_budget() const { return static_cast<long>(particles) * (static_cast<long>(iterations) + 1); }
};

// Minimises problem.fitness over problem.bounds(). Never throws for bad
// options, bad bounds or an exception from the fitness/progress callback:
// those end the run with Termination::failure, message why (best so far kept).
Summary pso_minimize(ProblemRef problem, const PsoOptions& options);

}  // namespace odotune::tuner

// An optimisation problem as the tuner sees it: a finite box and a scalar
// function to minimise over it. The tuner knows nothing else (no filters, no
// tracks); the objectives layer adapts its cost functions to this shape.
//
// A user problem is any plain struct (pagmo2 style) with
//
//   double fitness(std::span<const double> x) const;  // value to minimise
//   Bounds bounds() const;                             // the search box
//
// Contract for fitness():
//   * x.size() == bounds().lower.size(), and x lies inside the box.
//   * It must be thread-safe: the PSO solver calls it concurrently from
//     OpenMP threads (const, no shared mutable state without locking).
//   * It should return a finite value; for an infeasible or failed point,
//     return a large finite penalty. Non-finite values are tolerated (solvers
//     treat them as worse than every finite value and never report them as
//     the best) but they give derivative-free model-based methods (BOBYQA,
//     COBYLA, ...) nothing to work with.
//   * It may throw; the solvers turn an exception into
//     Termination::failure with message what() and never rethrow it.
//
// Optionally, a problem may also evaluate several points in one call (the
// robot_localization objective replays a batch of noise settings in lock
// step, rlnode::replay_batch):
//
//   void fitness_batch(std::span<const double> xs, std::span<double> out) const;
//     // out.size() points of bounds().dimension() values each, one after the
//     // other in xs; out[k] must be what fitness() gives for point k, to the
//     // bit, so that a solver's result does not depend on how it groups points.
//   int batch_size() const;  // how many points a call is best given (>= 1)
//
// The same contract as fitness() otherwise (thread-safe, points inside the
// box, may throw). pso_minimize hands a batch problem up to batch_size()
// particles per call; the other solvers call fitness().
//
// ProblemRef is a small non-owning, type-erased view of such a struct (like
// std::function_ref): it stores a pointer to the problem, so the problem must
// outlive every use of the ProblemRef. Passing a temporary directly to a
// solver call (`pso_minimize(Sphere{}, options)`) is fine; storing a
// ProblemRef to a temporary is not.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <span>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <odotune/core/why.h>

namespace odotune::tuner {

// The search box [lower, upper] (per-dimension, units of the problem's
// parameters). Valid when both have the same non-zero size, every bound is
// finite and lower[i] < upper[i].
struct Bounds {
  std::vector<double> lower;
  std::vector<double> upper;

  std::size_t dimension() const { return lower.size(); }
  // True if valid; otherwise false and, if why != nullptr, *why names the
  // first offending entry (e.g. "bounds: lower[1] = 3 is not < upper[1] = 2").
  bool IsValid(std::string* why) const;
  // True if x has the box's dimension and lower <= x <= upper component-wise.
  bool Contains(std::span<const double> x) const;
};

inline bool Bounds::IsValid(std::string* why) const {
  std::ostringstream msg;
  msg << "bounds: ";
  if (lower.size() != upper.size()) {
    msg << "lower has " << lower.size() << " entries but upper has " << upper.size()
        << "; expected the same number";
  } else if (lower.empty()) {
    msg << "empty box; expected at least one dimension";
  } else {
    std::size_t i = 0;
    for (; i < lower.size(); ++i)
      if (!(std::isfinite(lower[i]) && std::isfinite(upper[i]) && lower[i] < upper[i])) break;
    if (i == lower.size()) return true;
    msg << "lower[" << i << "] = " << lower[i] << ", upper[" << i << "] = " << upper[i]
        << "; expected finite values with lower < upper";
  }
  return core::invalid(why, msg.str());
}

inline bool Bounds::Contains(std::span<const double> x) const {
  if (x.size() != lower.size() || x.size() != upper.size()) return false;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!(lower[i] <= x[i] && x[i] <= upper[i])) return false;
  return true;
}

// What a user problem must provide (see the file comment for the contract).
template <typename T>
concept Problem = requires(const T& p, std::span<const double> x) {
  { p.fitness(x) } -> std::convertible_to<double>;
  { p.bounds() } -> std::convertible_to<Bounds>;
};

// A problem that can also evaluate several points in one call (see the file comment).
template <typename T>
concept BatchProblem = Problem<T> && requires(const T& p, std::span<const double> xs, std::span<double> out) {
  p.fitness_batch(xs, out);
  { p.batch_size() } -> std::convertible_to<int>;
};

class ProblemRef {
 public:
  // Non-owning: `problem` must outlive this ProblemRef (see file comment).
  template <Problem T>
    requires(!std::same_as<std::remove_cvref_t<T>, ProblemRef>)
  ProblemRef(const T& problem)  // NOLINT(google-explicit-constructor): by design
      : object_(&problem),
        fitness_([](const void* o, std::span<const double> x) -> double {
          return static_cast<const T*>(o)->fitness(x);
        }),
        bounds_([](const void* o) -> Bounds { return static_cast<const T*>(o)->bounds(); }) {
    if constexpr (BatchProblem<T>) {
      fitness_batch_ = [](const void* o, std::span<const double> xs, std::span<double> out) {
        static_cast<const T*>(o)->fitness_batch(xs, out);
      };
      batch_size_ = std::max(1, static_cast<int>(problem.batch_size()));
    }
  }

  double fitness(std::span<const double> x) const { return fitness_(object_, x); }
  Bounds bounds() const { return bounds_(object_); }
  // 1 for a problem without fitness_batch.
  int batch_size() const { return batch_size_; }
  // out[k] = fitness(point k of xs), by the problem's fitness_batch when it has one.
  void fitness_batch(std::span<const double> xs, std::span<double> out) const {
    if (fitness_batch_ != nullptr) {
      fitness_batch_(object_, xs, out);
      return;
    }
    const std::size_t dim = xs.size() / std::max<std::size_t>(out.size(), 1);
    for (std::size_t k = 0; k < out.size(); ++k) out[k] = fitness(xs.subspan(k * dim, dim));
  }

 private:
  const void* object_;
  double (*fitness_)(const void*, std::span<const double>);
  Bounds (*bounds_)(const void*);
  void (*fitness_batch_)(const void*, std::span<const double>, std::span<double>) = nullptr;
  int batch_size_ = 1;
};

}  // namespace odotune::tuner

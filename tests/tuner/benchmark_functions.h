// Classic test functions as plain tuner problems (see odotune/tuner/problem.h).
// Each has global minimum value 0 at a known point `optimum`, which is NOT the
// box centre, so that a local solver started at the centre gets no free win.
// All are pure functions of x, hence safe to call concurrently.
//
// Definitions as in the usual benchmark collections (e.g. M. Jamil & X.-S.
// Yang, "A literature survey of benchmark functions for global optimization
// problems", Int. J. Math. Model. Numer. Optim. 4(2), 2013):
//   sphere      f(x) = Σ (x_i − s_i)^2
//   Rosenbrock  f(x) = Σ_{i<n−1} 100 (x_{i+1} − x_i^2)^2 + (1 − x_i)^2,  optimum (1, …, 1)
//   Rastrigin   f(x) = 10 n + Σ (z_i^2 − 10 cos(2π z_i)),  z = x − s,    optimum s
#pragma once

#include <atomic>
#include <cmath>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include <odotune/tuner/problem.h>

namespace odotune::tuner::testing {

inline Bounds cube(std::size_t n, double half_width) {
  return {std::vector<double>(n, -half_width), std::vector<double>(n, half_width)};
}

// Shifted sphere in 3-D on [-5.12, 5.12]^3 (unimodal, separable).
struct Sphere {
  std::vector<double> optimum{1.5, -2.0, 0.75};
  double fitness(std::span<const double> x) const {
    double f = 0;
    for (std::size_t i = 0; i < x.size(); ++i) f += (x[i] - optimum[i]) * (x[i] - optimum[i]);
    return f;
  }
  Bounds bounds() const { return cube(optimum.size(), 5.12); }
};

// Rosenbrock's banana valley in 2-D on [-5.12, 5.12]^2 (unimodal, curved,
// badly conditioned); optimum (1, 1), f(centre) = 1.
struct Rosenbrock {
  std::vector<double> optimum{1.0, 1.0};
  double fitness(std::span<const double> x) const {
    double f = 0;
    for (std::size_t i = 0; i + 1 < x.size(); ++i) {
      const double a = x[i + 1] - x[i] * x[i];
      const double b = 1.0 - x[i];
      f += 100.0 * a * a + b * b;
    }
    return f;
  }
  Bounds bounds() const { return cube(optimum.size(), 5.12); }
};

// Shifted Rastrigin in 2-D on [-5.12, 5.12]^2 (highly multimodal: a local
// minimum near every integer offset from the optimum). From the centre the
// nearest local minimum is near z = (-1, 1), f ≈ 2.
struct Rastrigin {
  std::vector<double> optimum{1.3, -0.7};
  double fitness(std::span<const double> x) const {
    double f = 10.0 * static_cast<double>(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double z = x[i] - optimum[i];
      f += z * z - 10.0 * std::cos(2.0 * std::numbers::pi * z);
    }
    return f;
  }
  Bounds bounds() const { return cube(optimum.size(), 5.12); }
};

// Test instrumentation: forwards to `inner`, counts fitness calls and calls
// at points outside the box (thread-safe). `inner` must outlive the wrapper.
template <typename P>
struct Counted {
  explicit Counted(const P& p) : inner(p), box(p.bounds()) {}
  const P& inner;
  const Bounds box;
  mutable std::atomic<long> calls{0};
  mutable std::atomic<long> outside{0};
  double fitness(std::span<const double> x) const {
    calls.fetch_add(1, std::memory_order_relaxed);
    if (!box.Contains(x)) outside.fetch_add(1, std::memory_order_relaxed);
    return inner.fitness(x);
  }
  Bounds bounds() const { return inner.bounds(); }
};

}  // namespace odotune::tuner::testing

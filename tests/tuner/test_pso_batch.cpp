// pso_minimize on a batch problem (odotune/tuner/problem.h, fitness_batch): the same
// run, to the bit, as one evaluation at a time, for any batch size and thread
// count; batches never larger than batch_size(); a throwing batch fails the
// run.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <vector>

#include <odotune/tuner/pso.h>

#include "benchmark_functions.h"

namespace odotune::tuner {
namespace {

// Rastrigin evaluated `size` points per call, recording the largest call.
struct BatchRastrigin {
  testing::Rastrigin inner;
  int size = 8;
  mutable std::atomic<int> largest{0};
  mutable std::atomic<long> points{0};
  double fitness(std::span<const double> x) const { return inner.fitness(x); }
  Bounds bounds() const { return inner.bounds(); }
  int batch_size() const { return size; }
  void fitness_batch(std::span<const double> xs, std::span<double> out) const {
    const std::size_t dim = inner.optimum.size();
    EXPECT_EQ(xs.size(), out.size() * dim);
    for (std::size_t k = 0; k < out.size(); ++k) out[k] = inner.fitness(xs.subspan(k * dim, dim));
    int seen = largest.load();
    const int n = static_cast<int>(out.size());
    while (n > seen && !largest.compare_exchange_weak(seen, n)) {
    }
    points += n;
  }
};
static_assert(BatchProblem<BatchRastrigin>);
static_assert(!BatchProblem<testing::Rastrigin>);

Summary run_with_threads(ProblemRef p, const PsoOptions& o, int threads) {
  const int old_threads = omp_get_max_threads();
  omp_set_num_threads(threads);
  const Summary s = pso_minimize(p, o);
  omp_set_num_threads(old_threads);
  return s;
}

TEST(PsoBatch, SameRunAsOneEvaluationAtATime) {
  PsoOptions o;
  o.particles = 21;
  o.iterations = 30;
  o.seed = 77;
  const Summary one = run_with_threads(testing::Rastrigin{}, o, 1);
  ASSERT_TRUE(one.ok()) << one.termination_text();
  for (int size : {1, 3, 8, 64}) {
    for (int threads : {1, 2, 4}) {
      SCOPED_TRACE("batch " + std::to_string(size) + ", " + std::to_string(threads) + " threads");
      BatchRastrigin p;
      p.size = size;
      const Summary s = run_with_threads(p, o, threads);
      EXPECT_EQ(s.best_x, one.best_x);
      EXPECT_EQ(s.best_fitness, one.best_fitness);
      EXPECT_EQ(s.log, one.log);
      EXPECT_EQ(s.evaluations, one.evaluations);
      EXPECT_LE(p.largest.load(), std::min(size, o.particles));
      EXPECT_EQ(p.points.load(), size > 1 ? one.evaluations : 0);
    }
  }
}

TEST(PsoBatch, ThrowingBatchEndsInFailure) {
  struct Thrower : BatchRastrigin {
    void fitness_batch(std::span<const double>, std::span<double>) const {
      throw std::runtime_error("replay diverged");
    }
  };
  PsoOptions o;
  o.particles = 10;
  o.iterations = 3;
  const Summary s = pso_minimize(Thrower{}, o);
  EXPECT_EQ(s.termination, Termination::failure);
  EXPECT_EQ(s.termination_text(), "failure: replay diverged");
}

}  // namespace
}  // namespace odotune::tuner

// PSO contracts (determinism across thread counts, evaluation count, options
// validation, stop flag, failures) and the NLopt adapter's contracts
// (seeded reproducibility, exceptions, names, budget, stop, x0).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <odotune/core/counter_rng.h>
#include <odotune/tuner/nlopt_solver.h>
#include <odotune/tuner/pso.h>
#include <odotune/tuner/solver_choice.h>

#include "benchmark_functions.h"

namespace odotune::tuner {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
using testing::Counted;
using testing::Rastrigin;
using testing::Sphere;

// Runs `body` with `threads` OpenMP threads (dynamic adjustment off) and
// restores the previous settings.
template <typename F>
auto with_threads(int threads, F body) {
  const int old_threads = omp_get_max_threads();
  const int old_dynamic = omp_get_dynamic();
  omp_set_dynamic(0);
  omp_set_num_threads(threads);
  auto result = body();
  omp_set_num_threads(old_threads);
  omp_set_dynamic(old_dynamic);
  return result;
}

// Rastrigin that records the largest OpenMP team it was evaluated in. (Which
// threads of the team happen to take work depends on scheduling under load,
// so the team size is what can be asserted.)
struct ThreadRecording {
  Rastrigin inner;
  mutable std::atomic<int> max_team{0};
  double fitness(std::span<const double> x) const {
    const int team = omp_get_num_threads();
    int seen = max_team.load();
    while (team > seen && !max_team.compare_exchange_weak(seen, team)) {
    }
    return inner.fitness(x);
  }
  Bounds bounds() const { return inner.bounds(); }
};

void expect_identical(const Summary& a, const Summary& b) {
  EXPECT_EQ(a.best_x, b.best_x);  // exact, bit for bit
  EXPECT_EQ(a.best_fitness, b.best_fitness);
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.termination, b.termination);
  EXPECT_EQ(a.log, b.log);
}

PsoOptions small_pso(std::uint64_t seed) {
  PsoOptions o;
  o.particles = 24;
  o.iterations = 40;
  o.seed = seed;
  return o;
}

// ---------------------------------------------------------------- PSO ----

TEST(Pso, SameSeedIsBitIdenticalWith1_2And4Threads) {
  const PsoOptions o = small_pso(20240501);
  ThreadRecording p1, p2, p4;
  const Summary s1 = with_threads(1, [&] { return pso_minimize(p1, o); });
  const Summary s2 = with_threads(2, [&] { return pso_minimize(p2, o); });
  const Summary s4 = with_threads(4, [&] { return pso_minimize(p4, o); });
  ASSERT_TRUE(s1.ok()) << s1.termination_text();
  EXPECT_EQ(s1.log.size(), 41u);
  expect_identical(s1, s2);
  expect_identical(s1, s4);
  // The parallel path really ran: a team of 1 with 1 thread, of 4 with 4.
  EXPECT_EQ(p1.max_team.load(), 1);
  EXPECT_EQ(p4.max_team.load(), 4);
}

TEST(Pso, DifferentSeedsGiveDifferentRuns) {
  const Summary a = pso_minimize(Sphere{}, small_pso(1));
  const Summary b = pso_minimize(Sphere{}, small_pso(2));
  EXPECT_NE(a.best_x, b.best_x);
  ASSERT_FALSE(a.log.empty());
  ASSERT_FALSE(b.log.empty());
  EXPECT_NE(a.log.front().best_fitness, b.log.front().best_fitness);  // initial swarms differ
}

TEST(Pso, EvaluationCountIsParticlesTimesIterationsPlusOne) {
  struct Shape {
    int particles, iterations;
  };
  for (const Shape shape : {Shape{1, 0}, Shape{1, 5}, Shape{7, 3}, Shape{50, 150}}) {
    SCOPED_TRACE(std::to_string(shape.particles) + " particles, " + std::to_string(shape.iterations) +
                 " iterations");
    PsoOptions o;
    o.particles = shape.particles;
    o.iterations = shape.iterations;
    o.seed = 3;
    Sphere sphere;
    Counted<Sphere> counted(sphere);
    const Summary s = pso_minimize(counted, o);
    const long expected = static_cast<long>(shape.particles) * (shape.iterations + 1);
    EXPECT_EQ(s.termination_text(), "max_iterations");
    EXPECT_EQ(s.termination, Termination::max_iterations);
    EXPECT_EQ(counted.calls.load(), expected);
    EXPECT_EQ(s.evaluations, expected);
    EXPECT_EQ(o.evaluation_budget(), expected);
    EXPECT_EQ(s.iterations, shape.iterations);
    ASSERT_EQ(s.log.size(), static_cast<std::size_t>(shape.iterations) + 1);
    for (std::size_t k = 0; k < s.log.size(); ++k) {
      EXPECT_EQ(s.log[k].iteration, static_cast<int>(k));
      EXPECT_EQ(s.log[k].evaluations, static_cast<long>(shape.particles) * static_cast<long>(k + 1));
      if (k > 0) {
        EXPECT_LE(s.log[k].best_fitness, s.log[k - 1].best_fitness);
      }
    }
    EXPECT_EQ(s.log.back().best_fitness, s.best_fitness);
    EXPECT_EQ(sphere.fitness(s.best_x), s.best_fitness);
  }
}

// Absorbing walls: a particle leaving the box lands exactly on the bound,
// so an optimum in a corner is reached exactly and no point outside is
// ever evaluated.
TEST(Pso, OptimumInACornerIsReachedExactlyOnTheBounds) {
  struct Slope {
    double fitness(std::span<const double> x) const { return 10.0 - x[0] + x[1]; }
    Bounds bounds() const { return {{-1.0, -2.0}, {3.0, 0.5}}; }
  };
  Slope slope;
  Counted<Slope> counted(slope);
  const Summary s = pso_minimize(counted, small_pso(9));
  EXPECT_EQ(counted.outside.load(), 0);
  EXPECT_EQ(s.best_x, (std::vector<double>{3.0, -2.0}));
  EXPECT_EQ(s.best_fitness, 10.0 - 3.0 - 2.0);
}

TEST(Pso, DefaultsAreTheClercKennedyConstrictionCoefficients) {
  // χ = 2 / |2 − φ − sqrt(φ² − 4φ)| with φ = c1 + c2 = 4.1; c = χ·φ/2.
  const double phi = 4.1;
  const double chi = 2.0 / std::abs(2.0 - phi - std::sqrt(phi * phi - 4.0 * phi));
  const PsoOptions o;
  EXPECT_NEAR(o.inertia, chi, 1e-4);
  EXPECT_NEAR(o.cognitive, chi * phi / 2, 1e-4);
  EXPECT_NEAR(o.social, chi * phi / 2, 1e-4);
  EXPECT_EQ(o.particles, 50);
  EXPECT_EQ(o.iterations, 150);
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
}

TEST(Pso, InvalidOptionsAreRejectedWithAMessageNamingTheBadValue) {
  struct Bad {
    void (*mutate)(PsoOptions&);
    const char* expected;
  };
  const Bad bad[] = {
      {[](PsoOptions& o) { o.particles = 0; }, "particles = 0"},
      {[](PsoOptions& o) { o.iterations = -2; }, "iterations = -2"},
      {[](PsoOptions& o) { o.inertia = 1.5; }, "inertia = 1.5"},
      {[](PsoOptions& o) { o.inertia = std::numeric_limits<double>::quiet_NaN(); }, "inertia = nan"},
      {[](PsoOptions& o) { o.cognitive = -1; }, "cognitive = -1"},
      {[](PsoOptions& o) { o.social = std::numeric_limits<double>::infinity(); }, "social = inf"},
      {[](PsoOptions& o) { o.initial_velocity_fraction = 2; }, "initial_velocity_fraction = 2"},
      {[](PsoOptions& o) { o.max_velocity_fraction = 0; }, "max_velocity_fraction = 0"},
  };
  for (const Bad& b : bad) {
    SCOPED_TRACE(b.expected);
    PsoOptions o;
    b.mutate(o);
    std::string why;
    EXPECT_FALSE(o.IsValid(&why));
    EXPECT_THAT(why, HasSubstr(b.expected));
    EXPECT_FALSE(o.IsValid(nullptr));  // a null `why` is allowed
    Sphere sphere;
    Counted<Sphere> counted(sphere);
    const Summary s = pso_minimize(counted, o);
    EXPECT_THAT(s.termination_text(), StartsWith("failure: "));
    EXPECT_THAT(s.termination_text(), HasSubstr(b.expected));
    EXPECT_FALSE(s.ok());
    EXPECT_EQ(counted.calls.load(), 0);
    EXPECT_EQ(s.evaluations, 0);
  }
}

struct BadBox {
  Bounds box;
  double fitness(std::span<const double>) const { return 0; }
  Bounds bounds() const { return box; }
};

TEST(Pso, InvalidBoundsEndInAFailureNamingTheEntry) {
  const BadBox reversed{{{0, 3}, {1, 2}}};
  Summary s = pso_minimize(reversed, small_pso(1));
  EXPECT_THAT(s.termination_text(), StartsWith("failure: bounds: lower[1] = 3"));
  const BadBox infinite{{{0}, {std::numeric_limits<double>::infinity()}}};
  s = pso_minimize(infinite, small_pso(1));
  EXPECT_THAT(s.termination_text(), HasSubstr("upper[0] = inf"));
  const BadBox mismatched{{{0, 0}, {1}}};
  s = nlopt_minimize(mismatched, NloptOptions{});
  EXPECT_THAT(s.termination_text(), HasSubstr("lower has 2 entries but upper has 1"));
  EXPECT_EQ(s.evaluations, 0);
}

TEST(Pso, StopFlagRaisedByProgressStopsBeforeTheNextIteration) {
  std::atomic<bool> stop{false};
  const std::thread::id caller = std::this_thread::get_id();
  int calls = 0;
  bool off_thread = false;
  PsoOptions o = small_pso(5);
  o.stop = &stop;
  o.progress = [&](long done, long total) {
    ++calls;
    off_thread |= std::this_thread::get_id() != caller || omp_in_parallel() != 0;
    EXPECT_EQ(total, o.evaluation_budget());
    if (done >= 3L * o.particles) stop = true;  // after iteration 2
  };
  const Summary s = with_threads(2, [&] { return pso_minimize(Rastrigin{}, o); });
  EXPECT_EQ(s.termination_text(), "stopped");
  EXPECT_EQ(s.termination, Termination::stopped);
  EXPECT_EQ(s.evaluations, 3L * o.particles);
  EXPECT_EQ(s.iterations, 2);
  EXPECT_EQ(s.log.size(), 3u);
  EXPECT_EQ(calls, 3);
  EXPECT_FALSE(off_thread) << "progress must run on the calling thread, outside parallel regions";
  EXPECT_EQ(s.best_x.size(), 2u);
  EXPECT_TRUE(std::isfinite(s.best_fitness));
}

// A stop flag raised from elsewhere while the swarm is evaluating (as a
// Ctrl-C handler would) ends the run at the next iteration boundary.
TEST(Pso, StopFlagRaisedDuringEvaluationsStopsEarly) {
  struct Stopper {
    std::atomic<bool>* stop;
    mutable std::atomic<long> calls{0};
    double fitness(std::span<const double> x) const {
      if (calls.fetch_add(1) + 1 == 100) stop->store(true);
      return Sphere{}.fitness(x);
    }
    Bounds bounds() const { return Sphere{}.bounds(); }
  };
  std::atomic<bool> stop{false};
  Stopper p{&stop};
  PsoOptions o = small_pso(6);
  o.stop = &stop;
  const Summary s = with_threads(4, [&] { return pso_minimize(p, o); });
  EXPECT_EQ(s.termination_text(), "stopped");
  EXPECT_EQ(s.termination, Termination::stopped);
  EXPECT_LT(s.evaluations, o.evaluation_budget());
  EXPECT_EQ(s.evaluations % o.particles, 0);
  EXPECT_EQ(s.evaluations, 5L * o.particles);  // 100 falls in iteration 4 (evals 97..120)
}

TEST(Pso, ThrowingObjectiveEndsInFailureWithoutEscaping) {
  struct Thrower {
    double fitness(std::span<const double> x) const {
      if (x[0] > 4.0) throw std::runtime_error("model diverged at x0 > 4");
      return x[0] * x[0];
    }
    Bounds bounds() const { return testing::cube(2, 5.12); }
  };
  Summary s;
  EXPECT_NO_THROW(s = with_threads(4, [&] { return pso_minimize(Thrower{}, small_pso(7)); }));
  EXPECT_EQ(s.termination_text(), "failure: model diverged at x0 > 4");
  EXPECT_EQ(s.termination, Termination::failure);
  EXPECT_FALSE(s.ok());
}

// Most of the box is NaN or +inf (so particle 0 usually starts in a hole,
// which catches a NaN that sneaks in as the first global best); the finite
// region is x >= 3 component-wise with its minimum at (4, 4).
TEST(Pso, NonFiniteValuesAreNeverTheBest) {
  struct Holes {
    double fitness(std::span<const double> x) const {
      if (x[0] < 3.0) return std::numeric_limits<double>::quiet_NaN();
      if (x[1] < 3.0) return std::numeric_limits<double>::infinity();
      return (x[0] - 4.0) * (x[0] - 4.0) + (x[1] - 4.0) * (x[1] - 4.0);
    }
    Bounds bounds() const { return testing::cube(2, 5.12); }
  };
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Summary s = pso_minimize(Holes{}, small_pso(seed));
    ASSERT_TRUE(std::isfinite(s.best_fitness));
    EXPECT_GE(s.best_x[0], 3.0);
    EXPECT_GE(s.best_x[1], 3.0);
    EXPECT_LT(s.best_fitness, 1e-3);
    for (const LogRecord& r : s.log) EXPECT_FALSE(std::isnan(r.best_fitness));
  }
}

TEST(CounterRng, UniformInUnitIntervalAndKeyedOnEveryWord) {
  const int n = 100000;
  int bins[10] = {};
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double u = core::counter_uniform01(42, 3, static_cast<std::uint64_t>(i), 1, 2);
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    ++bins[static_cast<int>(u * 10)];
  }
  EXPECT_NEAR(sum / n, 0.5, 0.005);  // sd of the mean ≈ 0.0009
  double chi2 = 0;
  for (int b : bins) chi2 += (b - n / 10.0) * (b - n / 10.0) / (n / 10.0);
  EXPECT_LT(chi2, 27.9);  // 9 dof, p = 0.001
  const double base = core::counter_uniform01(1, 2, 3, 4, 5);
  EXPECT_EQ(base, core::counter_uniform01(1, 2, 3, 4, 5));
  EXPECT_NE(base, core::counter_uniform01(9, 2, 3, 4, 5));
  EXPECT_NE(base, core::counter_uniform01(1, 9, 3, 4, 5));
  EXPECT_NE(base, core::counter_uniform01(1, 2, 9, 4, 5));
  EXPECT_NE(base, core::counter_uniform01(1, 2, 3, 9, 5));
  EXPECT_NE(base, core::counter_uniform01(1, 2, 3, 4, 9));
  // Swapping key words changes the value (the hash is order-sensitive).
  EXPECT_NE(core::counter_uniform01(1, 2, 3, 4, 5), core::counter_uniform01(1, 3, 2, 4, 5));
}

// -------------------------------------------------------------- NLopt ----

NloptOptions crs2(std::uint64_t seed) {
  NloptOptions o;
  o.algorithm = "CRS2_LM";
  o.max_evaluations = 600;
  o.seed = seed;
  return o;
}

TEST(Nlopt, SameSeedGivesIdenticalResultForCrs2) {
  const Summary a = nlopt_minimize(Rastrigin{}, crs2(11));
  const Summary b = nlopt_minimize(Rastrigin{}, crs2(11));
  ASSERT_TRUE(a.ok()) << a.termination_text();
  expect_identical(a, b);
  const Summary c = nlopt_minimize(Rastrigin{}, crs2(12));
  EXPECT_NE(a.log, c.log);
  // Seeds differing only in their high 32 bits are different seeds too.
  const Summary d = nlopt_minimize(Rastrigin{}, crs2(11 + (1ULL << 40)));
  EXPECT_NE(a.log, d.log);
}

// NLopt's generator is thread-local in Debian's build (see nlopt_solver.h):
// runs on other threads, even concurrent ones, reproduce the seeded result.
TEST(Nlopt, ConcurrentSeededRunsOnOtherThreadsAreReproducible) {
  const Summary reference = nlopt_minimize(Rastrigin{}, crs2(21));
  Summary t1, t2;
  std::thread a([&] { t1 = nlopt_minimize(Rastrigin{}, crs2(21)); });
  std::thread b([&] { t2 = nlopt_minimize(Rastrigin{}, crs2(21)); });
  a.join();
  b.join();
  expect_identical(reference, t1);
  expect_identical(reference, t2);
}

TEST(Nlopt, ThrowingObjectiveEndsInFailureWithoutEscaping) {
  struct ThrowsLater {
    mutable long calls = 0;
    double fitness(std::span<const double> x) const {
      if (++calls == 10) throw std::runtime_error("simulation blew up");
      return Sphere{}.fitness(x);
    }
    Bounds bounds() const { return Sphere{}.bounds(); }
  };
  for (const char* algorithm : {"CRS2_LM", "BOBYQA", "DIRECT_L", "MLSL_LDS", "COBYLA"}) {
    SCOPED_TRACE(algorithm);
    ThrowsLater p;
    NloptOptions o;
    o.algorithm = algorithm;
    o.max_evaluations = 1000;
    Summary s;
    EXPECT_NO_THROW(s = nlopt_minimize(p, o));
    EXPECT_EQ(s.termination_text(), "failure: simulation blew up");
    EXPECT_EQ(s.termination, Termination::failure);
    EXPECT_EQ(s.evaluations, 10);
    EXPECT_EQ(p.calls, 10);
    EXPECT_EQ(s.best_x.size(), 3u);
    EXPECT_TRUE(std::isfinite(s.best_fitness));  // best of the 9 good evaluations
  }
}

TEST(Nlopt, UnknownAlgorithmIsRejectedListingTheValidNames) {
  NloptOptions o;
  o.algorithm = "SIMULATED_ANNEALING";
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("'SIMULATED_ANNEALING'"));
  for (const std::string& name : nlopt_algorithm_names()) EXPECT_THAT(why, HasSubstr(name));
  Sphere sphere;
  Counted<Sphere> counted(sphere);
  const Summary s = nlopt_minimize(counted, o);
  EXPECT_THAT(s.termination_text(), StartsWith("failure: nlopt: unknown algorithm"));
  EXPECT_EQ(counted.calls.load(), 0);

  o.algorithm = "crs2_lm";  // names are case-insensitive
  EXPECT_TRUE(o.IsValid(&why)) << why;
}

TEST(Nlopt, NamesAndClassification) {
  const std::vector<std::string>& names = nlopt_algorithm_names();
  for (const char* required :
       {"DIRECT_L", "CRS2_LM", "ISRES", "ESCH", "BOBYQA", "SBPLX", "NELDERMEAD", "COBYLA"})
    EXPECT_NE(std::find(names.begin(), names.end(), required), names.end()) << required;
  EXPECT_TRUE(nlopt_is_global("DIRECT_L"));
  EXPECT_TRUE(nlopt_is_global("isres"));
  EXPECT_TRUE(nlopt_is_global("MLSL_LDS"));
  EXPECT_FALSE(nlopt_is_global("BOBYQA"));
  EXPECT_FALSE(nlopt_is_global("NELDERMEAD"));
  EXPECT_FALSE(nlopt_is_global("NO_SUCH_THING"));
}

TEST(Nlopt, OtherInvalidOptionsNameTheBadValue) {
  NloptOptions o;
  o.max_evaluations = 0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("max_evaluations = 0"));
  o = NloptOptions{};
  o.xtol_rel = -1e-3;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("xtol_rel = -0.001"));
  o = NloptOptions{};
  o.x0 = std::vector<double>{0.0, std::numeric_limits<double>::quiet_NaN(), 0.0};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("x0[1] = nan"));
}

// Budgets below CRS2_LM's initial population (10·(n+1) = 40 points here)
// or small PRAXIS budgets make NLopt ask for more than maxeval: the adapter
// must still stop at the budget exactly.
TEST(Nlopt, BudgetIsRespectedAndReported) {
  struct Run {
    const char* algorithm;
    long budget;
  };
  for (const Run r :
       {Run{"CRS2_LM", 20}, Run{"CRS2_LM", 137}, Run{"PRAXIS", 30}, Run{"DIRECT_L", 101}, Run{"ESCH", 77}}) {
    SCOPED_TRACE(std::string(r.algorithm) + " with budget " + std::to_string(r.budget));
    Sphere sphere;
    Counted<Sphere> counted(sphere);
    NloptOptions o;
    o.algorithm = r.algorithm;
    o.max_evaluations = r.budget;
    o.xtol_rel = 0;  // PRAXIS: run to the budget
    const Summary s = nlopt_minimize(counted, o);
    EXPECT_EQ(s.termination_text(), "max_evaluations");
    EXPECT_EQ(s.termination, Termination::max_evaluations);
    EXPECT_EQ(s.evaluations, r.budget);
    EXPECT_EQ(counted.calls.load(), r.budget);
  }
}

TEST(Nlopt, StopFlagStopsBeforeTheNextEvaluation) {
  struct Stopper {
    std::atomic<bool>* stop;
    mutable long calls = 0;
    double fitness(std::span<const double> x) const {
      if (++calls == 50) stop->store(true);
      return Sphere{}.fitness(x);
    }
    Bounds bounds() const { return Sphere{}.bounds(); }
  };
  std::atomic<bool> stop{false};
  Stopper p{&stop};
  NloptOptions o = crs2(2);
  o.stop = &stop;
  const Summary s = nlopt_minimize(p, o);
  EXPECT_EQ(s.termination_text(), "stopped");
  EXPECT_EQ(s.termination, Termination::stopped);
  EXPECT_EQ(s.evaluations, 50);
  EXPECT_EQ(p.calls, 50);
}

TEST(Nlopt, LocalSolverStartsAtX0OrTheBoxCentre) {
  struct FirstPoint {
    mutable std::vector<double> first;
    double fitness(std::span<const double> x) const {
      if (first.empty()) first.assign(x.begin(), x.end());
      return Sphere{}.fitness(x);
    }
    Bounds bounds() const { return Sphere{}.bounds(); }
  };
  NloptOptions o;
  o.algorithm = "NELDERMEAD";
  FirstPoint centre;
  Summary s = nlopt_minimize(centre, o);
  EXPECT_EQ(centre.first, (std::vector<double>{0, 0, 0}));
  EXPECT_EQ(s.log.front().iteration, 1);
  EXPECT_EQ(s.log.front().best_fitness, Sphere{}.fitness(std::vector<double>{0, 0, 0}));

  o.x0 = std::vector<double>{-1, 2, 3};
  FirstPoint given;
  s = nlopt_minimize(given, o);
  EXPECT_EQ(given.first, *o.x0);
  EXPECT_LT(s.best_fitness, 1e-4);

  o.x0 = std::vector<double>{1, 2};
  s = nlopt_minimize(Sphere{}, o);
  EXPECT_EQ(s.termination_text(), "failure: nlopt: x0 has 2 entries, expected 3 (the box dimension)");
  o.x0 = std::vector<double>{1, 2, 6};
  s = nlopt_minimize(Sphere{}, o);
  EXPECT_THAT(s.termination_text(), StartsWith("failure: nlopt: x0 lies outside the box"));
  EXPECT_EQ(s.evaluations, 0);
}

TEST(Nlopt, ProgressRunsOnTheCallingThreadAndIsMonotone) {
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<long> seen;
  bool off_thread = false;
  NloptOptions o = crs2(3);
  o.max_evaluations = 1000;
  o.progress = [&](long done, long total) {
    off_thread |= std::this_thread::get_id() != caller;
    EXPECT_EQ(total, 1000);
    seen.push_back(done);
  };
  const Summary s = nlopt_minimize(Rastrigin{}, o);
  EXPECT_FALSE(off_thread);
  ASSERT_FALSE(seen.empty());
  EXPECT_LE(seen.size(), 101u);
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_EQ(seen.back(), s.evaluations);
}

// The end of a run as a kind and a message; its text is what outputs and
// stores have always printed.
TEST(Summary, TerminationTextKeepsTheWordsOutputsPrint) {
  Summary s;
  s.termination = Termination::max_iterations;
  EXPECT_EQ(s.termination_text(), "max_iterations");
  EXPECT_TRUE(s.ok());
  s.termination = Termination::solver_criterion, s.message = "nlopt: XTOL_REACHED";
  EXPECT_EQ(s.termination_text(), "nlopt: XTOL_REACHED");
  EXPECT_TRUE(s.ok());
  s.termination = Termination::failure, s.message = "bounds: lower[1] = 3 > upper[1] = 2";
  EXPECT_EQ(s.termination_text(), "failure: bounds: lower[1] = 3 > upper[1] = 2");
  EXPECT_FALSE(s.ok());
  EXPECT_STREQ(to_string(Termination::stopped), "stopped");
  EXPECT_STREQ(to_string(Termination::max_evaluations), "max_evaluations");
}

// A solver is named once, as the user writes it, and printed the same way.
TEST(SolverChoice, ParsesWhatUsersWriteAndRefusesTheRestByName) {
  std::string why;
  const std::optional<SolverChoice> pso = SolverChoice::parse("pso", &why);
  ASSERT_TRUE(pso.has_value());
  EXPECT_EQ(pso->kind, SolverChoice::Kind::pso);
  EXPECT_EQ(pso->name(), "pso");
  const std::optional<SolverChoice> sbplx = SolverChoice::parse("nlopt:SBPLX", &why);
  ASSERT_TRUE(sbplx.has_value()) << why;
  EXPECT_EQ(sbplx->kind, SolverChoice::Kind::nlopt);
  EXPECT_EQ(sbplx->nlopt_algorithm, "SBPLX");
  EXPECT_EQ(sbplx->name(), "nlopt:SBPLX");
  for (const std::string& n : nlopt_algorithm_names()) {
    const std::optional<SolverChoice> c = SolverChoice::parse("nlopt:" + n, &why);
    ASSERT_TRUE(c.has_value()) << n << ": " << why;
    EXPECT_EQ(SolverChoice::parse(c->name(), nullptr), c) << n;  // round trip
  }
  EXPECT_FALSE(SolverChoice::parse("annealing", &why).has_value());
  EXPECT_EQ(why, "solver 'annealing': expected pso or nlopt:NAME");
  EXPECT_FALSE(SolverChoice::parse("nlopt:NOPE", &why).has_value());
  EXPECT_THAT(why, StartsWith("nlopt: unknown algorithm 'NOPE'"));
  EXPECT_FALSE(SolverChoice::parse("PSO", &why).has_value());
}

}  // namespace
}  // namespace odotune::tuner

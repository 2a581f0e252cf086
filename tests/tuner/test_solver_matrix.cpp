// Solver × function matrix (in the spirit of NLopt's own test program): every
// solver the tuner offers (PSO and every name in nlopt_algorithm_names()) is
// run on every benchmark function of benchmark_functions.h.
//
// Pass criteria, per run:
//   * the Summary is consistent: not a failure, 0 < evaluations <= budget and
//     equal to the fitness calls actually made, all of them inside the box,
//     best_x inside the box with
//     fitness(best_x) == best_fitness, a non-empty, non-increasing log that
//     ends at best_fitness;
//   * a global solver reaches the global optimum (value 0) of all three
//     functions: best_fitness <= its tolerance in kCases below;
//   * a local solver (started at the box centre) reaches the optimum of
//     sphere and Rosenbrock (best_fitness <= 1e-4); on Rastrigin it must only
//     return a finite value <= the value at its start point.
//
// Tolerances and budgets: 1e-4 for every solver except the two evolution
// strategies, which are known to converge slowly and to stagnate near the
// optimum. Their budgets/populations/tolerances below were chosen from a
// 30-seed sweep (worst best_fitness over seeds 0..29 in brackets):
//   ISRES (30000 evals, population 150): sphere [4e-12], Rosenbrock [2e-9],
//     Rastrigin [0.17]: tolerance 0.5 there = "found the global basin", as
//     every other local minimum of Rastrigin has f >= 0.99.
//   ESCH (100000 evals, population 200): sphere [4e-5] -> 1e-3, Rosenbrock
//     [0.07] -> 0.25, Rastrigin [0.02] -> 0.25. ESCH reaches f <= 1e-3 on
//     Rosenbrock in only ~20 % of seeds even with 1e6 evaluations, so the
//     Rosenbrock bar for ESCH is "deep inside the valley", not the optimum.
// All other cells passed 1e-4 on all 30 seeds with a margin of >= 5x.
// Stochastic solvers are checked on 3 seeds per cell.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <odotune/tuner/nlopt_solver.h>
#include <odotune/tuner/pso.h>

#include "benchmark_functions.h"

namespace odotune::tuner {
namespace {

using testing::Counted;
using testing::Rastrigin;
using testing::Rosenbrock;
using testing::Sphere;

enum class Fn { kSphere, kRosenbrock, kRastrigin };

std::string fn_name(Fn f) {
  switch (f) {
    case Fn::kSphere: return "sphere";
    case Fn::kRosenbrock: return "rosenbrock";
    case Fn::kRastrigin: return "rastrigin";
  }
  return "?";
}

// Expectations for one solver. tol[f] is the bound on best_fitness; for a
// local solver on Rastrigin only "finite and <= start value" is required.
struct Case {
  std::string solver;
  long budget;          // max evaluations (PSO: particles × (iterations + 1))
  unsigned population;  // NLopt population, 0 = default
  int seeds;            // runs with seeds 1..seeds
  double tol[3];        // sphere, Rosenbrock, Rastrigin
};

const PsoOptions kPso{};  // the defaults: 50 particles, 150 iterations

const std::vector<Case>& cases() {
  static const std::vector<Case> kCases = {
      {"pso", kPso.evaluation_budget(), 0, 3, {1e-4, 1e-4, 1e-4}},
      {"DIRECT", 7550, 0, 1, {1e-4, 1e-4, 1e-4}},
      {"DIRECT_L", 7550, 0, 1, {1e-4, 1e-4, 1e-4}},
      {"DIRECT_L_RAND", 7550, 0, 3, {1e-4, 1e-4, 1e-4}},
      {"CRS2_LM", 7550, 0, 3, {1e-4, 1e-4, 1e-4}},
      {"ISRES", 30000, 150, 3, {1e-4, 1e-4, 0.5}},
      {"ESCH", 100000, 200, 3, {1e-3, 0.25, 0.25}},
      // Sobol-sequence based: the seed hardly matters; MLSL's bookkeeping is
      // quadratic in evaluations, so one run per cell keeps the test fast.
      {"MLSL_LDS", 7550, 0, 1, {1e-4, 1e-4, 1e-4}},
      {"BOBYQA", 7550, 0, 1, {1e-4, 1e-4, 0}},
      {"SBPLX", 7550, 0, 1, {1e-4, 1e-4, 0}},
      {"NELDERMEAD", 7550, 0, 1, {1e-4, 1e-4, 0}},
      {"COBYLA", 7550, 0, 1, {1e-4, 1e-4, 0}},
      {"PRAXIS", 7550, 0, 3, {1e-4, 1e-4, 0}},
  };
  return kCases;
}

std::vector<std::string> all_solvers() {
  std::vector<std::string> names{"pso"};
  for (const std::string& n : nlopt_algorithm_names()) names.push_back(n);
  return names;
}

const Case* find_case(const std::string& solver) {
  for (const Case& c : cases())
    if (c.solver == solver) return &c;
  return nullptr;
}

bool is_global(const std::string& solver) { return solver == "pso" || nlopt_is_global(solver); }

Summary run(const Case& c, ProblemRef problem, std::uint64_t seed) {
  if (c.solver == "pso") {
    PsoOptions o = kPso;
    o.seed = seed;
    return pso_minimize(problem, o);
  }
  NloptOptions o;
  o.algorithm = c.solver;
  o.max_evaluations = c.budget;
  o.population = c.population;
  o.seed = seed;
  return nlopt_minimize(problem, o);
}

class SolverMatrix : public ::testing::TestWithParam<std::tuple<std::string, Fn>> {};

template <typename P>
void check_cell(const Case& c, Fn fn, const P& problem) {
  const Bounds box = problem.bounds();
  std::vector<double> centre(box.dimension());
  for (std::size_t d = 0; d < centre.size(); ++d) centre[d] = 0.5 * (box.lower[d] + box.upper[d]);
  const double f_start = problem.fitness(centre);
  const bool global = is_global(c.solver);
  const double tol = c.tol[static_cast<int>(fn)];

  for (int seed = 1; seed <= c.seeds; ++seed) {
    SCOPED_TRACE("solver " + c.solver + " on " + fn_name(fn) + ", seed " + std::to_string(seed));
    Counted<P> counted(problem);
    const Summary s = run(c, counted, static_cast<std::uint64_t>(seed));

    // Consistency of the Summary.
    ASSERT_TRUE(s.ok()) << s.termination_text();
    EXPECT_GT(s.evaluations, 0);
    EXPECT_LE(s.evaluations, c.budget);
    EXPECT_EQ(s.evaluations, counted.calls.load());
    EXPECT_EQ(counted.outside.load(), 0) << "fitness called outside the box";
    ASSERT_EQ(s.best_x.size(), box.dimension());
    EXPECT_TRUE(box.Contains(s.best_x));
    EXPECT_EQ(problem.fitness(s.best_x), s.best_fitness);
    ASSERT_FALSE(s.log.empty());
    EXPECT_EQ(s.log.back().best_fitness, s.best_fitness);
    for (std::size_t k = 1; k < s.log.size(); ++k) {
      EXPECT_LE(s.log[k].best_fitness, s.log[k - 1].best_fitness) << "log record " << k;
      EXPECT_GE(s.log[k].evaluations, s.log[k - 1].evaluations) << "log record " << k;
    }
    EXPECT_LE(s.log.back().evaluations, s.evaluations);

    // Quality.
    ASSERT_TRUE(std::isfinite(s.best_fitness));
    if (global || fn != Fn::kRastrigin) {
      EXPECT_LE(s.best_fitness, tol) << "best_x[0] = " << s.best_x[0] << ", termination "
                                     << s.termination_text();
    } else {
      EXPECT_LE(s.best_fitness, f_start);
    }
  }
}

TEST_P(SolverMatrix, ReachesExpectedOptimumWithinBudget) {
  const auto& [solver, fn] = GetParam();
  const Case* c = find_case(solver);
  ASSERT_NE(c, nullptr) << "no expectation row for solver " << solver
                        << ": add it to cases() in test_solver_matrix.cpp";
  switch (fn) {
    case Fn::kSphere: check_cell(*c, fn, Sphere{}); break;
    case Fn::kRosenbrock: check_cell(*c, fn, Rosenbrock{}); break;
    case Fn::kRastrigin: check_cell(*c, fn, Rastrigin{}); break;
  }
}

INSTANTIATE_TEST_SUITE_P(AllSolversAllFunctions, SolverMatrix,
                         ::testing::Combine(::testing::ValuesIn(all_solvers()),
                                            ::testing::Values(Fn::kSphere, Fn::kRosenbrock, Fn::kRastrigin)),
                         [](const ::testing::TestParamInfo<SolverMatrix::ParamType>& param_info) {
                           return std::get<0>(param_info.param) + "_" + fn_name(std::get<1>(param_info.param));
                         });

// The matrix is over every solver: a row without a solver would be dead.
TEST(SolverMatrixTable, EveryRowNamesAnOfferedSolver) {
  const std::vector<std::string> offered = all_solvers();
  for (const Case& c : cases())
    EXPECT_NE(std::find(offered.begin(), offered.end(), c.solver), offered.end()) << c.solver;
  EXPECT_EQ(cases().size(), offered.size());
}

// Sanity of the benchmark definitions themselves: value 0 at the stated
// optimum, and the optimum is not the box centre.
TEST(BenchmarkFunctions, OptimumIsZeroAndOffCentre) {
  auto check = [](const auto& p) {
    EXPECT_EQ(p.fitness(p.optimum), 0.0);
    const Bounds b = p.bounds();
    EXPECT_TRUE(b.IsValid(nullptr));
    EXPECT_TRUE(b.Contains(p.optimum));
    std::vector<double> centre(b.dimension(), 0.0);
    EXPECT_GT(p.fitness(centre), 0.5);
    // A small step from the optimum increases f.
    std::vector<double> x = p.optimum;
    x[0] += 1e-3;
    EXPECT_GT(p.fitness(x), 0.0);
  };
  check(Sphere{});
  check(Rosenbrock{});
  check(Rastrigin{});
  // Rastrigin's nearest non-global local minimum (one unit off) is ~0.995.
  Rastrigin r;
  std::vector<double> x = r.optimum;
  x[0] += 1.0;
  EXPECT_NEAR(r.fitness(x), 1.0, 0.01);
}

}  // namespace
}  // namespace odotune::tuner

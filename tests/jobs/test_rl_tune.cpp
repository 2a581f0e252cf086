// Every solver the tuner offers (PSO and each NLopt algorithm) on the
// robot_localization objective (objectives/rl_objective.h) of a small
// synthetic GPS drive: the run ends well, stays in the box, reports a best
// point whose fitness it is, and a local start is never made worse.
#include <cmath>
#include <fstream>

#include <omp.h>

#include <gtest/gtest.h>

#include "jobs/tune_job.h"
#include "objectives/rl_objective.h"
#include "rlnode/gps_alignment.h"
#include "rlnode/params.h"
#include "rlnode/recording.h"
#include "support/rl_gps_bag.h"
#include "support/temp_dir.h"
#include "tuner/nlopt_solver.h"

namespace {

using namespace odotune;

struct Fixture {
  testing_support::TempDir dir{"rl-tune"};
  rlnode::Recording rec;
  Fixture() {
    const auto params = dir.path() / "p.yaml";
    std::ofstream(params) << testing_support::kRlGpsParams;
    rec = rlnode::load_recording(testing_support::rl_gps_bag(dir.path(), 0.4), rlnode::read_rl_params(params));
    rec.gps_transform = rlnode::fit_gps_alignment(rec, rlnode::settings_of(rec.params), 30.0).transform;
  }
};

RlTuneOptions small_options(const rlnode::Recording& rec) {
  RlTuneOptions o;
  o.fitness = RlFitness::both;
  o.space = RlNoiseSpace::blocks;
  o.outage_s = 15.0;
  o.until_ns = rec.start_ns + 60'000'000'000LL;
  return o;
}

}  // namespace

TEST(RlTune, EverySolverRunsOnTheRobotLocalizationObjective) {
  Fixture f;
  const RlObjective objective(f.rec, rlnode::settings_of(f.rec.params), small_options(f.rec));
  ASSERT_EQ(objective.space().dim(), 5u + 2u);  // 5 noise blocks, 2 inputs' covariances
  const BoxProblem<RlObjective> problem{&objective};
  const auto [lo, hi] = objective.bounds();
  std::vector<double> centre(lo.size());
  for (std::size_t i = 0; i < lo.size(); ++i) centre[i] = 0.5 * (lo[i] + hi[i]);
  const double at_centre = objective.fitness(centre);
  ASSERT_TRUE(std::isfinite(at_centre));

  std::vector<std::string> solvers = {"pso"};
  for (const std::string& n : tuner::nlopt_algorithm_names()) solvers.push_back("nlopt:" + n);
  for (const std::string& solver : solvers) {
    SolverSettings s;
    s.solver = solver;
    s.seed = 2;
    s.particles = 5;
    s.iterations = 4;  // 25 evaluations, as the NLopt budget
    const tuner::Summary sum = run_solver(problem, s);
    EXPECT_TRUE(sum.ok()) << solver << ": " << sum.termination;
    EXPECT_GT(sum.evaluations, 0) << solver;
    EXPECT_LE(sum.evaluations, 25) << solver;
    ASSERT_EQ(sum.best_x.size(), lo.size()) << solver;
    for (std::size_t i = 0; i < lo.size(); ++i) {
      EXPECT_GE(sum.best_x[i], lo[i]) << solver;
      EXPECT_LE(sum.best_x[i], hi[i]) << solver;
    }
    EXPECT_EQ(objective.fitness(sum.best_x), sum.best_fitness) << solver;
    // NLopt starts at the box's centre: its best is never worse than that.
    if (solver != "pso") {
      EXPECT_LE(sum.best_fitness, at_centre) << solver;
    }
  }
}

TEST(RlTune, SameSeedGivesTheSameTuneWithOneOrTwoThreads) {
  Fixture f;
  const RlObjective objective(f.rec, rlnode::settings_of(f.rec.params), small_options(f.rec));
  const BoxProblem<RlObjective> problem{&objective};
  SolverSettings s;
  s.seed = 7;
  s.particles = 6;
  s.iterations = 3;
  omp_set_num_threads(1);
  const tuner::Summary a = run_solver(problem, s);
  omp_set_num_threads(2);
  const tuner::Summary b = run_solver(problem, s);
  EXPECT_EQ(a.best_x, b.best_x);
  EXPECT_EQ(a.best_fitness, b.best_fitness);
  EXPECT_EQ(a.log, b.log);
}

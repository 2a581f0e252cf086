// Every solver the tuner offers (PSO and each NLopt algorithm) on the
// robot_localization objective (odotune/objectives/rl_objective.h) of a small
// synthetic GPS drive: the run ends well, stays in the box, reports a best
// point whose fitness it is, and a local start is never made worse.
#include <cmath>
#include <fstream>

#include <omp.h>

#include <gtest/gtest.h>

#include <odotune/jobs/rl_search.h>
#include <odotune/jobs/tune_job.h>
#include <odotune/objectives/rl_objective.h>
#include <odotune/rlnode/gps_alignment.h>
#include <odotune/rlnode/params.h>
#include <odotune/rlnode/recording.h>
#include <odotune/tuner/nlopt_solver.h>

#include "support/rl_gps_bag.h"
#include "support/temp_dir.h"

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

objectives::RlTuneOptions small_options(const rlnode::Recording& rec) {
  objectives::RlTuneOptions o;
  o.fitness = objectives::RlFitness::both;
  o.space = objectives::RlNoiseSpace::blocks;
  o.outage_s = {15.0};
  o.until_ns = rec.start_ns + 60'000'000'000LL;
  return o;
}

}  // namespace

TEST(RlTune, EverySolverRunsOnTheRobotLocalizationObjective) {
  Fixture f;
  const objectives::RlObjective objective(f.rec, rlnode::settings_of(f.rec.params), small_options(f.rec));
  ASSERT_EQ(objective.space().dim(), 5u + 2u);  // 5 noise blocks, 2 inputs' covariances
  const jobs::BoxProblem<objectives::RlObjective> problem{&objective};
  const auto [lo, hi] = objective.bounds();
  std::vector<double> centre(lo.size());
  for (std::size_t i = 0; i < lo.size(); ++i) centre[i] = 0.5 * (lo[i] + hi[i]);
  const double at_centre = objective.fitness(centre);
  ASSERT_TRUE(std::isfinite(at_centre));

  std::vector<std::string> solvers = {"pso"};
  for (const std::string& n : tuner::nlopt_algorithm_names()) solvers.push_back("nlopt:" + n);
  for (const std::string& solver : solvers) {
    jobs::SolverSettings s;
    s.solver = tuner::SolverChoice::parse(solver, nullptr).value();
    s.seed = 2;
    s.particles = 5;
    s.iterations = 4;  // 25 evaluations, as the NLopt budget
    const tuner::Summary sum = jobs::run_solver(problem, s);
    EXPECT_TRUE(sum.ok()) << solver << ": " << sum.termination_text();
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
  const objectives::RlObjective objective(f.rec, rlnode::settings_of(f.rec.params), small_options(f.rec));
  const jobs::BoxProblem<objectives::RlObjective> problem{&objective};
  jobs::SolverSettings s;
  s.seed = 7;
  s.particles = 6;
  s.iterations = 3;
  omp_set_num_threads(1);
  const tuner::Summary a = jobs::run_solver(problem, s);
  omp_set_num_threads(2);
  const tuner::Summary b = jobs::run_solver(problem, s);
  EXPECT_EQ(a.best_x, b.best_x);
  EXPECT_EQ(a.best_fitness, b.best_fitness);
  EXPECT_EQ(a.log, b.log);
}

// A stored run's factors, applied by name (as export and report do), give
// the settings the objective replayed, in both spaces; names that are not the
// filter's are refused.
TEST(RlTune, FactorsAppliedByNameGiveTheObjectivesSettings) {
  Fixture f;
  const rlnode::ReplaySettings base = rlnode::settings_of(f.rec.params);
  for (objectives::RlNoiseSpace space :
       {objectives::RlNoiseSpace::diagonal, objectives::RlNoiseSpace::blocks}) {
    objectives::RlTuneOptions o = small_options(f.rec);
    o.space = space;
    const objectives::RlObjective objective(f.rec, base, o);
    const auto [lo, hi] = objective.bounds();
    std::vector<double> x(lo.size());
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = lo[i] + (hi[i] - lo[i]) * (0.1 + 0.8 * static_cast<double>(i) / static_cast<double>(x.size()));
    std::vector<std::string> names;
    for (const objectives::ParamSpec& p : objective.space().params()) names.push_back(p.name);
    const std::vector<double> factors = objective.space().to_physical(x);
    rlnode::ReplaySettings s = base;
    std::string why;
    ASSERT_TRUE(objectives::apply_rl_factors(f.rec.params, names, factors, &s, &why)) << why;
    const rlnode::ReplaySettings want = objective.settings_at(x);
    EXPECT_EQ(s.process_noise, want.process_noise) << objectives::to_string(space);
    EXPECT_EQ(s.covariance_scale, want.covariance_scale) << objectives::to_string(space);
    EXPECT_NE(s.process_noise, base.process_noise);
  }
  rlnode::ReplaySettings s = base;
  std::string why;
  const std::vector<std::string> bad = {"q_warp"};
  const std::vector<double> one = {2.0};
  EXPECT_FALSE(objectives::apply_rl_factors(f.rec.params, bad, one, &s, &why));
  EXPECT_NE(why.find("q_warp"), std::string::npos) << why;
  const std::vector<std::string> good = {"q_x"};
  const std::vector<double> negative = {-1.0};
  EXPECT_FALSE(objectives::apply_rl_factors(f.rec.params, good, negative, &s, &why));
  // two_d_mode: a block leaves the entries the mode forces alone.
  EXPECT_EQ(objectives::rl_noise_members("q_position", true), std::vector<int>({0, 1}));
  EXPECT_EQ(objectives::rl_noise_members("q_position", false), std::vector<int>({0, 1, 2}));
}

TEST(RlTune, FitnessNamesAndStoredModesRoundTrip) {
  for (objectives::RlFitness fit :
       {objectives::RlFitness::heldout_fixes, objectives::RlFitness::outage, objectives::RlFitness::both,
        objectives::RlFitness::innovation_nll, objectives::RlFitness::nis, objectives::RlFitness::whiteness,
        objectives::RlFitness::heldout_nll}) {
    objectives::RlFitness back{};
    ASSERT_TRUE(objectives::parse_rl_fitness(objectives::to_string(fit), &back));
    EXPECT_EQ(back, fit);
    EXPECT_EQ(objectives::rl_fitness_of_mode(objectives::stored_mode(fit)), fit);
  }
  EXPECT_EQ(objectives::stored_mode(objectives::RlFitness::heldout_fixes), 8);  // mode 8 on this filter too
  EXPECT_EQ(objectives::stored_mode(objectives::RlFitness::heldout_nll), 15);
  EXPECT_FALSE(objectives::rl_fitness_of_mode(7).has_value());
  objectives::RlFitness untouched = objectives::RlFitness::both;
  EXPECT_FALSE(objectives::parse_rl_fitness("gt", &untouched));
  EXPECT_EQ(untouched, objectives::RlFitness::both);
}

// The staged search (odotune/jobs/rl_search.h): the grid is deterministic; a start's parameters either were determined
// (their range leaves out the file's value) or were reset to the file's value,
// and the reset costs less than the tolerance; same seed, same start with one
// or two threads.
TEST(RlTune, StagedSearchResetsWhatTheRecordingDoesNotDetermine) {
  Fixture f;
  objectives::RlTuneOptions o = small_options(f.rec);
  o.space = objectives::RlNoiseSpace::diagonal;
  o.input_covariances = false;
  const objectives::RlObjective objective(f.rec, rlnode::settings_of(f.rec.params), o);
  objectives::RlSearchOptions search;
  search.grid_levels = {-1.0, 1.0};
  search.refine_decades = 0.5;
  search.profile_step_decades = 2.0;
  jobs::SolverSettings s;
  s.seed = 3;
  s.particles = 6;
  s.iterations = 3;
  omp_set_num_threads(1);
  const jobs::RlGridResult grid = jobs::rl_grid_stage(objective, search, s);
  const jobs::RlStartResult a = jobs::rl_refine_and_profile(objective, grid, search, s);
  omp_set_num_threads(2);
  const jobs::RlGridResult grid2 = jobs::rl_grid_stage(objective, search, s);
  const jobs::RlStartResult b = jobs::rl_refine_and_profile(objective, grid2, search, s);
  EXPECT_EQ(grid.x, grid2.x);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.fitness, b.fitness);

  EXPECT_GT(grid.evaluations, 32);  // 2 levels ^ 5 blocks, then the profile
  ASSERT_EQ(a.profiles.size(), objective.space().dim());
  const std::vector<double> factors = objective.space().to_physical(a.x);
  int undetermined = 0;
  for (std::size_t i = 0; i < factors.size(); ++i) {
    const jobs::RlParamProfile& p = a.profiles[i];
    EXPECT_LE(p.lo, p.hi);
    if (!p.determined) {
      ++undetermined;
      EXPECT_EQ(factors[i], 1.0) << objective.space().params()[i].name;
      EXPECT_LE(p.lo, 1.0);
      EXPECT_GE(p.hi, 1.0);
    } else {
      EXPECT_GE(factors[i], p.lo * (1 - 1e-12)) << objective.space().params()[i].name;
      EXPECT_LE(factors[i], p.hi * (1 + 1e-12)) << objective.space().params()[i].name;
    }
  }
  // This drive measures no acceleration: its block cannot matter.
  EXPECT_GT(undetermined, 0);
  EXPECT_LE(a.fitness, a.refined_fitness * (1.0 + search.tolerance));
  EXPECT_EQ(a.fitness, objective.data_fitness(a.x));
}

// Normal operation is not traded for outages: with keep_heldout, a
// candidate worse than the file at held-out fixes scores above the file.
TEST(RlTune, WorseAtHeldOutFixesScoresAboveTheFile) {
  Fixture f;
  objectives::RlTuneOptions o = small_options(f.rec);
  o.fitness = objectives::RlFitness::outage;
  o.input_covariances = false;
  const objectives::RlObjective keep(f.rec, rlnode::settings_of(f.rec.params), o);
  o.keep_heldout = false;
  const objectives::RlObjective trade(f.rec, rlnode::settings_of(f.rec.params), o);
  const auto [lo, hi] = keep.bounds();
  int worse = 0;
  for (int k = 0; k < 12; ++k) {
    std::vector<double> x(lo.size());
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = lo[i] + (hi[i] - lo[i]) * std::fmod(0.37 * static_cast<double>(k * 7 + i * 3) + 0.1, 1.0);
    const objectives::FixScore h = keep.heldout_score(keep.settings_at(x));
    if (h.rmse_m > keep.baseline_heldout().rmse_m) {
      ++worse;
      EXPECT_GT(keep.data_fitness(x), keep.baseline_fitness()) << k;
    } else {
      EXPECT_EQ(keep.data_fitness(x), trade.data_fitness(x)) << k;
    }
  }
  EXPECT_GT(worse, 0);
}

// The field's criteria (odotune/objectives/rl_innovations.h) as the tune's fitness:
// finite at the file and across the box, and under the same guard: a
// candidate worse than the file at held-out fixes scores above the file.
TEST(RlTune, FieldCriteriaAreFiniteAndGuarded) {
  Fixture f;
  for (objectives::RlFitness fit : {objectives::RlFitness::innovation_nll, objectives::RlFitness::nis,
                                    objectives::RlFitness::whiteness, objectives::RlFitness::heldout_nll}) {
    objectives::RlTuneOptions o = small_options(f.rec);
    o.fitness = fit;
    o.input_covariances = false;
    const objectives::RlObjective objective(f.rec, rlnode::settings_of(f.rec.params), o);
    EXPECT_EQ(objective.batch_size(), 1) << objectives::to_string(fit);
    ASSERT_TRUE(std::isfinite(objective.baseline_fitness())) << objectives::to_string(fit);
    const auto [lo, hi] = objective.bounds();
    int worse = 0;
    for (int k = 0; k < 8; ++k) {
      std::vector<double> x(lo.size());
      for (std::size_t i = 0; i < x.size(); ++i)
        x[i] = lo[i] + (hi[i] - lo[i]) * std::fmod(0.41 * static_cast<double>(k * 5 + i * 3) + 0.2, 1.0);
      const double v = objective.data_fitness(x);
      EXPECT_FALSE(std::isnan(v)) << objectives::to_string(fit) << " " << k;
      if (objective.heldout_score(objective.settings_at(x)).rmse_m > objective.baseline_heldout().rmse_m) {
        ++worse;
        EXPECT_GT(v, objective.baseline_fitness()) << objectives::to_string(fit) << " " << k;
      }
    }
    EXPECT_GT(worse, 0) << objectives::to_string(fit);
  }
}

// The objective's batch (candidates replayed in lock step) gives each
// candidate's single fitness, bit for bit, also for a part batch.
TEST(RlTune, BatchFitnessIsEachCandidatesOwn) {
  Fixture f;
  objectives::RlTuneOptions o = small_options(f.rec);
  o.prior_weight = 0.01;
  const objectives::RlObjective objective(f.rec, rlnode::settings_of(f.rec.params), o);
  const auto [lo, hi] = objective.bounds();
  const std::size_t dim = lo.size();
  for (std::size_t n : {std::size_t{3}, std::size_t{8}, std::size_t{11}}) {
    std::vector<double> xs;
    for (std::size_t k = 0; k < n; ++k)
      for (std::size_t i = 0; i < dim; ++i)
        xs.push_back(lo[i] +
                     (hi[i] - lo[i]) * std::fmod(0.29 * static_cast<double>(k * 5 + i * 7) + 0.05, 1.0));
    std::vector<double> out(n);
    objective.fitness_batch(xs, out);
    std::vector<double> data(n);
    objective.data_fitness_batch(xs, data);
    for (std::size_t k = 0; k < n; ++k) {
      const std::span<const double> x(&xs[k * dim], dim);
      EXPECT_EQ(out[k], objective.fitness(x)) << n << " " << k;
      EXPECT_EQ(data[k], objective.data_fitness(x)) << n << " " << k;
    }
  }
}

// The calibration study's computation helpers (odotune/studies/calibration_study.h),
// its tables and figure data (odotune/studies/study_tables.h, odotune/studies/study_outputs.h)
// on a short wheelchair drive; `odotune study` end to end is
// tests/cli/test_cli_study.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <odotune/studies/calibration_study.h>
#include <odotune/studies/study_outputs.h>
#include <odotune/studies/study_tables.h>

#include "support/study_fixtures.h"

namespace odotune::studies {
namespace {

using odotune::studies::MeanSd;
using namespace odotune::study_fixtures;

TEST(StudyMeanSd, SampleStatisticsOverFiniteValues) {
  const MeanSd m = odotune::studies::mean_sd({1.0, 2.0, 3.0, 4.0});
  EXPECT_EQ(m.n, 4);
  EXPECT_DOUBLE_EQ(m.mean, 2.5);
  EXPECT_NEAR(m.sd, std::sqrt(5.0 / 3.0), 1e-15);  // Σ(x − 2.5)² = 5, n − 1 = 3
  const MeanSd with_nan = odotune::studies::mean_sd({NAN, 2.0, NAN, 4.0});
  EXPECT_EQ(with_nan.n, 2);
  EXPECT_DOUBLE_EQ(with_nan.mean, 3.0);
  EXPECT_NEAR(with_nan.sd, std::sqrt(2.0), 1e-15);
  const MeanSd one = odotune::studies::mean_sd({7.0});
  EXPECT_EQ(one.n, 1);
  EXPECT_DOUBLE_EQ(one.sd, 0.0);
  const MeanSd none = odotune::studies::mean_sd({NAN});
  EXPECT_EQ(none.n, 0);
  EXPECT_TRUE(std::isnan(none.mean) && std::isnan(none.sd));
  EXPECT_EQ(odotune::studies::mean_sd_text(none), "–");
  EXPECT_EQ(odotune::studies::mean_sd_text(m), "2.5 ± 1.3");
}

TEST(StudyOptions, IsValidNamesTheBadValue) {
  odotune::studies::StudyOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.runs = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("runs = 0"), std::string::npos) << why;
  o = {};
  o.truth_radius_spread = 0.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("truth_radius_spread"), std::string::npos) << why;
  o = {};
  o.pf_particles = 3;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("pf_particles = 3"), std::string::npos) << why;
}

TEST(StudyDraws, SeedPerRunTruthWithinSpreadDkfWithinThePfRanges) {
  odotune::studies::StudyOptions o;
  o.seed = 40;
  o.truth_radius_spread = 0.02;
  const sim::Scenario sc = parsed(10.0);
  std::map<double, int> seen;
  for (int r = 0; r < 20; ++r) {
    const odotune::studies::McDraw d = odotune::studies::mc_draw(o, sc, r);
    EXPECT_EQ(d.seed, 40u + static_cast<unsigned>(r));
    for (double s : {d.truth_scale_l, d.truth_scale_r}) {
      EXPECT_GE(s, 0.98);
      EXPECT_LE(s, 1.02);
      ++seen[s];
    }
    const filters::PfCalibratorParams ranges;
    EXPECT_GE(d.dkf_initial.wheel_radius_right_m, ranges.wheel_radius_right_m.lo);
    EXPECT_LE(d.dkf_initial.wheel_radius_right_m, ranges.wheel_radius_right_m.hi);
    EXPECT_GE(d.dkf_initial.wheel_radius_left_m, ranges.wheel_radius_left_m.lo);
    EXPECT_LE(d.dkf_initial.wheel_radius_left_m, ranges.wheel_radius_left_m.hi);
    EXPECT_DOUBLE_EQ(d.dkf_initial.wheel_base_m, 0.65);
    // Deterministic.
    const odotune::studies::McDraw again = odotune::studies::mc_draw(o, sc, r);
    EXPECT_EQ(again.truth_scale_l, d.truth_scale_l);
    EXPECT_EQ(again.dkf_initial.wheel_radius_left_m, d.dkf_initial.wheel_radius_left_m);
    // The run's scenario: its seed and truth, other effects kept.
    const sim::Scenario rs = odotune::studies::run_scenario(sc, d);
    EXPECT_EQ(rs.seed, d.seed);
    ASSERT_TRUE(rs.effects.radius_error.has_value());
    EXPECT_EQ(rs.effects.radius_error->scale_l, d.truth_scale_l);
    EXPECT_EQ(rs.effects.radius_error->scale_r, d.truth_scale_r);
    ASSERT_TRUE(rs.effects.wheel_base_error && rs.effects.radius_step);
    EXPECT_DOUBLE_EQ(rs.effects.radius_step->t, 10.0);
  }
  EXPECT_EQ(seen.size(), 40u);  // every draw different
}

TEST(StudyScenarioCheck, RejectsRobotsOutsideThePfRangesAndMissingSensors) {
  const odotune::studies::StudyOptions o;
  EXPECT_NO_THROW(odotune::studies::check_study_scenario(parsed(), o));
  sim::Scenario small = parsed();
  small.robot.wheel_radius_left_m = small.robot.wheel_radius_right_m = 0.05;
  try {
    odotune::studies::check_study_scenario(small, o);
    ADD_FAILURE() << "accepted 0.05 m wheels";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("short_chair"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("outside the PF's initial range"), std::string::npos) << e.what();
  }
  sim::Scenario blind = parsed();
  blind.sensors.ext_velocity.enabled = false;
  EXPECT_THROW(odotune::studies::check_study_scenario(blind, o), std::invalid_argument);
}

TEST(StudyConvergence, ReachedAndSettledPerPieceOfTheTruth) {
  // Truth 0.32 m both wheels until t = 10 s, then 0.31 m. Tolerance 0.5 %:
  // 1.6 mm before, 1.55 mm after.
  calibration::TruthSchedule truth;
  truth.from_s = {-INFINITY, 10.0};
  truth.params = {{0.32, 0.32, 0.65}, {0.31, 0.31, 0.65}};
  odotune::studies::ParamTrace tr;
  // Estimates at t = 0.5, 1.0, ..., 20: R_R enters the band at 2 s, leaves at
  // 3 s, re-enters at 4 s for good; R_L is within from the start. After the
  // step both are off until 13 s (3 s after the change), then within.
  for (int i = 1; i <= 40; ++i) {
    const double t = 0.5 * i;
    double rr = 0.32, rl = 0.3205;
    if (t < 2.0 || (t >= 3.0 && t < 4.0)) rr = 0.325;
    if (t >= 10.0) rr = rl = t < 13.0 ? 0.32 : 0.3101;
    tr.t_s.push_back(t);
    tr.r_right_m.push_back(rr);
    tr.r_left_m.push_back(rl);
    tr.wheel_base_m.push_back(0.9);  // far off: must not matter
  }
  const auto c = odotune::studies::radius_convergence(tr, truth, 0.5, 0.005);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_DOUBLE_EQ(c[0].reached_s, 2.0 - 0.5);
  EXPECT_DOUBLE_EQ(c[0].settled_s, 4.0 - 0.5);
  EXPECT_DOUBLE_EQ(c[1].reached_s, 3.0);
  EXPECT_DOUBLE_EQ(c[1].settled_s, 3.0);
  // Never within after the change → NaN.
  for (std::size_t i = 0; i < tr.t_s.size(); ++i)
    if (tr.t_s[i] >= 10.0) tr.r_left_m[i] = 0.33;
  const auto never = odotune::studies::radius_convergence(tr, truth, 0.5, 0.005);
  EXPECT_TRUE(std::isnan(never[1].reached_s));
  EXPECT_TRUE(std::isnan(never[1].settled_s));
}

TEST(StudyFigureData, ResamplingBarsAreNormalisedByTheLargestMean) {
  odotune::studies::ResamplingStudy s;
  for (auto r : odotune::studies::table1_resamplers())
    for (auto p : odotune::studies::table1_policies()) {
      odotune::studies::ResamplingCell c;
      c.resampler = r;
      c.policy = p;
      s.cells.push_back(c);
    }
  // Errors (|R_R| + |R_L|)/2 per run: cell 0 → {1, 3} mm (mean 2), cell 5 → {4, 4} mm (mean 4).
  for (std::size_t i = 0; i < s.cells.size(); ++i) s.cells[i].runs = {{0.001, 0.001}, {0.001, 0.001}};
  s.cells[0].runs = {{0.001, 0.001}, {0.002, 0.004}};
  s.cells[5].runs = {{0.004, 0.004}, {0.003, 0.005}};
  for (auto& c : s.cells) c.ms_per_iteration = {1.0, 0.1, 2};
  s.cells[7].ms_per_iteration = {2.0, 0.5, 2};
  const odotune::studies::ResamplingBars b = odotune::studies::resampling_bars(s);
  ASSERT_EQ(b.groups.size(), 4u);
  ASSERT_EQ(b.series.size(), 3u);
  ASSERT_EQ(b.panels.size(), 2u);
  // Cell 5 = group 1 (multinomial), series 2 (every); cell 0 = group 0, series 0.
  EXPECT_EQ(b.groups[1], "multinomial");
  EXPECT_EQ(b.series[2], "every");
  EXPECT_DOUBLE_EQ(b.panels[0].mean[1][2], 1.0);
  EXPECT_DOUBLE_EQ(b.panels[0].mean[0][0], 0.5);
  EXPECT_NEAR(b.panels[0].sd[0][0], std::sqrt(2.0) * 0.001 / 0.004, 1e-12);  // sd of {1, 3} mm / 4 mm
  EXPECT_DOUBLE_EQ(b.panels[0].mean[2][0], 0.25);
  // Time: cell 7 = group 2 (residual), series 1 (max) is the slowest.
  EXPECT_DOUBLE_EQ(b.panels[1].mean[2][1], 1.0);
  EXPECT_DOUBLE_EQ(b.panels[1].sd[2][1], 0.25);
  EXPECT_DOUBLE_EQ(b.panels[1].mean[0][0], 0.5);
}

// The computation in-process: the numbers do not depend on the thread count.
TEST(StudyResampling, SameNumbersForOneAndTwoThreads) {
  odotune::studies::StudyOptions o;
  o.runs = 2;
  o.seed = 11;
  o.pf_particles = 300;
  const sim::Scenario sc = parsed();
  o.threads = 1;
  const odotune::studies::ResamplingStudy a = odotune::studies::run_resampling_study(sc, o);
  o.threads = 2;
  const odotune::studies::ResamplingStudy b = odotune::studies::run_resampling_study(sc, o);
  ASSERT_EQ(a.cells.size(), 12u);
  EXPECT_EQ(without_timing(odotune::studies::table1_runs_csv(a)),
            without_timing(odotune::studies::table1_runs_csv(b)));
  EXPECT_EQ(a.threads_used, 1);
  EXPECT_EQ(b.threads_used, 2);
  // The every-step policy resamples at every iteration; N_eff less often.
  for (const auto& c : a.cells) {
    if (c.policy == filters::ResamplePolicy::every_step) {
      EXPECT_DOUBLE_EQ(c.resampled_fraction.mean, 1.0);
    }
    if (c.policy == filters::ResamplePolicy::neff) {
      EXPECT_LT(c.resampled_fraction.mean, 1.0);
    }
  }
}

}  // namespace
}  // namespace odotune::studies

// diagnose() end to end on simulated tracks (sim_track.h), and the residual
// series it locates on.
#include <odotune/diagnose/diagnosis.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/diagnose/residual_series.h>
#include <odotune/diagnose/window_replay.h>

#include "diagnose/sim_track.h"

namespace odotune::diagnose {
namespace {

using testing_support::SimTrackOptions;
using testing_support::simulate_track;

SimTrackOptions options(std::uint64_t seed, double duration_s, std::vector<std::string> effects) {
  SimTrackOptions o;
  o.duration_s = duration_s;
  o.seed = seed;
  o.wheel_radius_left_m = 0.07, o.wheel_radius_right_m = 0.0702;
  o.wheel_base_m = 0.38, o.ticks_per_rev = 3000;
  o.odo_rate_hz = 50.0, o.gt_rate_hz = 50.0, o.gt_sigma_m = 0.005;
  o.gyro_rate_hz = 50.0, o.gyro_sigma_rad_s = 0.002;
  o.effects = std::move(effects);
  return o;
}

DiagInput simulated(const SimTrackOptions& o) { return build_diag_input(simulate_track(o)); }

const Finding* finding(const Diagnosis& d, std::string_view effect) {
  for (const Finding& f : d.findings)
    if (f.name() == effect) return &f;
  return nullptr;
}

std::string names(const Diagnosis& d) {
  std::string s;
  for (const Finding& f : d.findings) s += std::string(f.name()) + " ";
  return s;
}

TEST(ResidualSeries, KinematicsFollowTheOdometryAndRowsFollowTheWindows) {
  const DiagInput in = simulated(options(81, 60.0, {}));
  const std::vector<Window> windows = make_windows(in, 20.0);
  const ReplayResult r = replay(in, EffectSet{}, 20.0);
  const ResidualSeries s = residual_series(in, windows, r);
  std::string why;
  ASSERT_TRUE(s.IsValid(&why)) << why;
  std::size_t scored = 0;
  for (const Window& w : windows) scored += w.ref_end - w.ref_begin;
  EXPECT_EQ(s.t_s.size(), scored);
  // The base lap holds straights at 0.5-0.8 m/s, 0.4 m/s corners of 0.6 m
  // radius (w = 0.67 rad/s) and spins at 90 deg/s.
  double v_max = 0.0, w_max = 0.0;
  for (std::size_t i = 0; i < s.t_s.size(); ++i) {
    v_max = std::max(v_max, s.v_mps[i]);
    w_max = std::max(w_max, std::abs(s.w_radps[i]));
    ASSERT_TRUE(std::isfinite(s.accel_mps2[i]));
  }
  EXPECT_NEAR(v_max, 0.8, 0.05);
  EXPECT_NEAR(w_max, std::numbers::pi / 2.0, 0.1);
  // Errors are the replay's predictions minus the reference.
  const std::size_t i = s.t_s.size() / 2;
  const auto it = std::find(in.ref_t_s.begin(), in.ref_t_s.end(), s.t_s[i]);
  ASSERT_NE(it, in.ref_t_s.end());
  const auto g = static_cast<std::size_t>(it - in.ref_t_s.begin());
  EXPECT_DOUBLE_EQ(s.ex_m[i], r.pred_x_m[g] - in.ref_x_m[g]);
  EXPECT_DOUBLE_EQ(s.ey_m[i], r.pred_y_m[g] - in.ref_y_m[g]);
}

TEST(ResidualSeries, MismatchedReplayIsAnError) {
  const DiagInput in = simulated(options(82, 30.0, {}));
  ReplayResult r = replay(in, EffectSet{}, 10.0);
  r.pred_x_m.pop_back();
  EXPECT_THROW(residual_series(in, make_windows(in, 10.0), r), std::invalid_argument);
}

TEST(DiagnoseOptions, DefaultsAreValidAndBadValuesAreNamed) {
  std::string why;
  EXPECT_TRUE(DiagnoseOptions{}.IsValid(&why)) << why;
  DiagnoseOptions o;
  o.unexplained_min_share = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, ::testing::HasSubstr("unexplained_min_share"));
  o = {};
  o.locate.threshold_sigma = -1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, ::testing::StartsWith("locate: "));
  EXPECT_THROW(diagnose(simulated(options(83, 30.0, {})), o), std::invalid_argument);
}

TEST(Diagnose, NoEffectGivesNoFinding) {
  const Diagnosis d = diagnose(simulated(options(84, 120.0, {})));
  EXPECT_TRUE(d.findings.empty()) << names(d);
  EXPECT_TRUE(d.model.empty()) << d.model.to_string();
  EXPECT_DOUBLE_EQ(d.final_pos_rmse_m, d.baseline_pos_rmse_m);
}

TEST(Diagnose, LateralSkidIsNamedLocatedInTurnsAndProvedOnHeldOutWindows) {
  const Diagnosis d = diagnose(simulated(options(85, 150.0, {"lateral_skid:k=0.04"})));
  ASSERT_EQ(d.findings.size(), 1u) << names(d);
  const Finding& f = d.findings.front();
  EXPECT_TRUE(f.is(Effect::lateral_skid)) << f.name();
  ASSERT_EQ(f.params.size(), 1u);
  EXPECT_EQ(f.params[0].name, "k");
  EXPECT_NEAR(f.param("k"), 0.04, 0.25 * 0.04);
  ASSERT_EQ(f.stderrs.size(), 1u);
  EXPECT_GT(f.stderrs[0].value, 0.0);
  EXPECT_LT(f.stderrs[0].value, 0.01);
  EXPECT_FALSE(f.segments.empty());
  for (const TimeSegment& s : f.segments) EXPECT_LT(s.t0_s, s.t1_s);
  EXPECT_FALSE(f.conditions.empty());
  EXPECT_GT(f.explains, 0.5);
  EXPECT_LE(f.explains, 1.0);
  EXPECT_LT(f.heldout.after_pos_rmse_m, f.heldout.before_pos_rmse_m);
  EXPECT_LT(f.train.after_pos_rmse_m, f.train.before_pos_rmse_m);
  // One finding: its "before" is the nominal model, so it matches the overall numbers.
  EXPECT_DOUBLE_EQ(f.heldout.before_pos_rmse_m, d.heldout.before_pos_rmse_m);
  EXPECT_LT(d.final_pos_rmse_m, d.baseline_pos_rmse_m);
  EXPECT_TRUE(d.model.on(Effect::lateral_skid));
  // The simulator's form parses back to the same value.
  EXPECT_NEAR(EffectSet::parse({f.spec()}).get(Effect::lateral_skid, "k"), f.param("k"), 1e-12);
}

TEST(Diagnose, GyroBiasIsJudgedAgainstTheReferenceHeading) {
  SimTrackOptions o = options(86, 120.0, {"gyro_bias:b=0.004"});
  const Diagnosis d = diagnose(simulated(o));
  const Finding* f = finding(d, "gyro_bias");
  ASSERT_NE(f, nullptr) << names(d);
  EXPECT_EQ(d.findings.size(), 1u) << names(d);
  EXPECT_NEAR(f->param("b"), 0.004, 0.25 * 0.004);
  EXPECT_GT(f->stderrs[0].value, 0.0);
  EXPECT_LT(f->heldout.after_pos_rmse_m, f->heldout.before_pos_rmse_m);
  EXPECT_GT(f->explains, 0.0);
  EXPECT_TRUE(d.model.on(Effect::gyro_bias));
  // A gyro effect does not touch wheel dead reckoning.
  EXPECT_DOUBLE_EQ(d.final_pos_rmse_m, d.baseline_pos_rmse_m);
}

TEST(Diagnose, TwoEffectsAreBothFoundMostImportantFirst) {
  const Diagnosis d = diagnose(
      simulated(options(87, 150.0, {"radius_error:scale_l=0.994,scale_r=1.003", "gyro_bias:b=0.003"})));
  ASSERT_NE(finding(d, "radius_error"), nullptr) << names(d);
  ASSERT_NE(finding(d, "gyro_bias"), nullptr) << names(d);
  for (std::size_t i = 1; i < d.findings.size(); ++i)
    EXPECT_GE(d.findings[i - 1].explains, d.findings[i].explains);
}

// physics-effects.md's odometry_bias: the odometry reads v + b_v, w + b_w, so
// it creeps at the stops. Named with both offsets within 3 standard errors
// or 10 % of the truth, proved on held-out windows, and written back in the
// simulator's form (what --scenario-out replays).
TEST(Diagnose, OdometryBiasIsNamedWithItsOffsets) {
  const double b_v = 0.004, b_w = -0.003;
  const Diagnosis d = diagnose(simulated(options(89, 150.0, {"odometry_bias:b_v=0.004,b_w=-0.003"})));
  ASSERT_EQ(d.findings.size(), 1u) << names(d);
  const Finding& f = d.findings.front();
  ASSERT_TRUE(f.is(Effect::odometry_bias)) << f.name();
  ASSERT_EQ(f.params.size(), 2u);
  ASSERT_EQ(f.stderrs.size(), 2u);
  for (const auto& [name, truth] : {std::pair<std::string, double>{"b_v", b_v}, {"b_w", b_w}}) {
    const std::size_t i = name == "b_v" ? 0 : 1;
    EXPECT_EQ(f.params[i].name, name);
    const double se = f.stderrs[i].value;
    EXPECT_GT(se, 0.0) << name;
    EXPECT_LE(std::abs(f.param(name) - truth), std::max(3.0 * se, 0.1 * std::abs(truth)))
        << name << " = " << f.param(name) << " +- " << se << ", truth " << truth;
  }
  EXPECT_LT(f.heldout.after_pos_rmse_m, f.heldout.before_pos_rmse_m);
  EXPECT_LT(d.final_pos_rmse_m, 0.5 * d.baseline_pos_rmse_m);
  EXPECT_TRUE(d.model.on(Effect::odometry_bias));
  const EffectSet back = EffectSet::parse({f.spec()});
  EXPECT_EQ(back.get(Effect::odometry_bias, "b_v"), f.param("b_v"));
  EXPECT_EQ(back.get(Effect::odometry_bias, "b_w"), f.param("b_w"));
}

TEST(Diagnose, IsDeterministic) {
  const DiagInput in = simulated(options(88, 90.0, {"lateral_skid:k=0.04"}));
  const Diagnosis a = diagnose(in), b = diagnose(in);
  ASSERT_EQ(a.findings.size(), b.findings.size());
  for (std::size_t i = 0; i < a.findings.size(); ++i) EXPECT_EQ(a.findings[i].spec(), b.findings[i].spec());
  EXPECT_EQ(a.final_pos_rmse_m, b.final_pos_rmse_m);
}

}  // namespace
}  // namespace odotune::diagnose

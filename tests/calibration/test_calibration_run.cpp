// Running and scoring odometry calibration (odotune/calibration/calibration_run.h):
// method names, the convergence-time rule on hand-made traces, dead-reckoning
// scores of fixed parameters against an independent integration of the
// ticks, and the online calibrators (DKF, adaptive PF) and the batch fit on
// simulated wheelchair tracks whose true parameters are known.
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_run.h>

#include "support/calibration_track.h"

namespace odotune::calibration {
namespace {

using ::testing::HasSubstr;
using testing_support::chair_track;
using testing_support::chair_truth;
using testing_support::ChairTrackOptions;
using filters::OdometryParams;

constexpr double kRunScaleL = testing_support::kMisalignedScaleL,
                 kRunScaleR = testing_support::kMisalignedScaleR,
                 kRunScaleBase = testing_support::kMisalignedScaleBase;

const tracks::Track& track_120() {
  static const tracks::Track t = chair_track(testing_support::misaligned_chair(120.0, 21));
  return t;
}
const CalibrationInput& input_120() {
  static const CalibrationInput in = build_calibration_input(track_120(), {});
  return in;
}

bool within(const OdometryParams& p, const OdometryParams& truth, double tol) {
  return std::abs(p.wheel_radius_left_m / truth.wheel_radius_left_m - 1.0) <= tol &&
         std::abs(p.wheel_radius_right_m / truth.wheel_radius_right_m - 1.0) <= tol &&
         std::abs(p.wheel_base_m / truth.wheel_base_m - 1.0) <= tol;
}

OdometryParams params(double rl, double rr, double d) {
  OdometryParams p;
  p.wheel_radius_left_m = rl;
  p.wheel_radius_right_m = rr;
  p.wheel_base_m = d;
  return p;
}

// Independent dead reckoning straight from the track's ticks and ground
// truth (midpoint rule of track-format.md): RMSE of (x, y) and of θ.
std::pair<double, double> reference_dead_reckoning(const tracks::Track& track, const OdometryParams& p) {
  const double k = 2.0 * std::numbers::pi / *track.meta().ticks_per_rev;
  double x = track.col(tracks::Col::gt_x)[0], y = track.col(tracks::Col::gt_y)[0],
         th = track.col(tracks::Col::gt_theta)[0];
  double ss_pos = 0, ss_th = 0;
  int n = 0;
  for (std::size_t i = 1; i < track.size(); ++i) {
    const double l = static_cast<double>(track.ticks_l()[i] - track.ticks_l()[i - 1]) * k *
                     p.wheel_radius_left_m;
    const double r = static_cast<double>(track.ticks_r()[i] - track.ticks_r()[i - 1]) * k *
                     p.wheel_radius_right_m;
    const double dth = (r - l) / p.wheel_base_m;
    x += 0.5 * (l + r) * std::cos(th + 0.5 * dth);
    y += 0.5 * (l + r) * std::sin(th + 0.5 * dth);
    th += dth;
    const double ex = x - track.col(tracks::Col::gt_x)[i], ey = y - track.col(tracks::Col::gt_y)[i];
    const double eth = std::remainder(th - track.col(tracks::Col::gt_theta)[i], 2.0 * std::numbers::pi);
    ss_pos += ex * ex + ey * ey;
    ss_th += eth * eth;
    ++n;
  }
  return {std::sqrt(ss_pos / n), std::sqrt(ss_th / n)};
}

TEST(CalibrationMethodNames, RoundTrip) {
  for (CalibrationMethod m :
       {CalibrationMethod::adaptive_pf, CalibrationMethod::pf, CalibrationMethod::dkf,
        CalibrationMethod::batch_pose, CalibrationMethod::batch_velocity, CalibrationMethod::none}) {
    CalibrationMethod back = CalibrationMethod::none;
    ASSERT_TRUE(parse_calibration_method(to_string(m), &back)) << to_string(m);
    EXPECT_EQ(back, m);
  }
  EXPECT_EQ(to_string(CalibrationMethod::adaptive_pf), "adaptive-pf");
  CalibrationMethod untouched = CalibrationMethod::dkf;
  EXPECT_FALSE(parse_calibration_method("adaptive_pf", &untouched));
  EXPECT_FALSE(parse_calibration_method("", &untouched));
  EXPECT_EQ(untouched, CalibrationMethod::dkf);
}

TEST(CalibrationOptions, ValidationAndAdaptiveParticleRule) {
  CalibrationOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.convergence_tolerance = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("convergence_tolerance"));
  o = {};
  o.method = CalibrationMethod::pf;
  o.pf.particles = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("pf."));
  o = {};
  o.method = CalibrationMethod::dkf;
  o.dkf.initial_sd_radius_m = -1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("dkf."));
  o.method = CalibrationMethod::batch_velocity;  // the DKF parameters are not used
  EXPECT_TRUE(o.IsValid(&why)) << why;

  // adaptive-pf: the plain default count becomes 8000; any other is kept.
  o = {};
  o.method = CalibrationMethod::adaptive_pf;
  EXPECT_TRUE(effective_pf_params(o).adaptive);
  EXPECT_EQ(effective_pf_params(o).particles, 8000);
  o.pf.particles = 3000;
  EXPECT_EQ(effective_pf_params(o).particles, 3000);
  o.method = CalibrationMethod::pf;
  o.pf.adaptive = true;
  EXPECT_FALSE(effective_pf_params(o).adaptive);
  o.pf.particles = filters::PfCalibratorParams{}.particles;
  EXPECT_EQ(effective_pf_params(o).particles, filters::PfCalibratorParams{}.particles);
}

TEST(ConvergenceTime, HandMadeTraces) {
  const OdometryParams truth = params(0.30, 0.32, 0.60);
  const OdometryParams in = params(0.3014, 0.3185, 0.6029);  // all within 0.5 %
  const OdometryParams out_r = params(0.30, 0.322, 0.60);    // R_R 0.625 % off
  const OdometryParams out_d = params(0.30, 0.32, 0.596);    // D 0.67 % off
  const std::vector<double> t = {1, 2, 3, 4, 5, 6};
  EXPECT_EQ(convergence_time(t, {out_r, in, out_r, in, in, in}, truth, 0.005), std::optional<double>(4.0));
  EXPECT_EQ(convergence_time(t, {in, in, in, in, in, in}, truth, 0.005), std::optional<double>(1.0));
  EXPECT_EQ(convergence_time(t, {in, in, in, in, in, out_r}, truth, 0.005), std::nullopt);
  // The wheel base is reported but not part of convergence (the paper's
  // convergence is the radii's, Fariña et al. §VI).
  EXPECT_EQ(convergence_time(t, {out_r, in, out_d, in, in, out_d}, truth, 0.005), std::optional<double>(2.0));
  // A looser tolerance accepts the 0.625 % radius.
  EXPECT_EQ(convergence_time(t, {in, out_r, in, out_d, in, in}, truth, 0.005), std::optional<double>(3.0));
  EXPECT_EQ(convergence_time(t, {in, out_r, in, out_d, in, in}, truth, 0.0065), std::optional<double>(1.0));
  // Exactly at the tolerance counts as converged (binary-exact numbers).
  const OdometryParams half = params(0.5, 0.5, 0.5);
  EXPECT_EQ(convergence_time({1.0}, {params(0.625, 0.5, 0.375)}, half, 0.25), std::optional<double>(1.0));
  EXPECT_EQ(convergence_time({1.0}, {params(0.625, 0.5, 0.375)}, half, 0.24), std::nullopt);
  EXPECT_EQ(convergence_time({}, {}, truth, 0.005), std::nullopt);
  EXPECT_THROW(convergence_time({1.0, 2.0}, {in}, truth, 0.005), std::invalid_argument);
}

TEST(CalibrationScore, NoneIsNominalDeadReckoningAndTruthIsFarBetter) {
  const tracks::Track& track = track_120();
  const CalibrationInput& in = input_120();
  const OdometryParams truth = chair_truth(kRunScaleL, kRunScaleR, kRunScaleBase);

  CalibrationOptions o;
  o.method = CalibrationMethod::none;
  const CalibrationResult none = run_calibration({&in}, o);
  ASSERT_EQ(none.tracks.size(), 1u);
  const TrackCalibrationScore& s = none.tracks[0];
  EXPECT_EQ(s.track, track.name());
  EXPECT_EQ(none.iterations, 0);
  EXPECT_DOUBLE_EQ(none.final_params.wheel_base_m, 0.65);
  ASSERT_EQ(none.trace.t.size(), 1u);  // fixed parameters: one row per track
  EXPECT_DOUBLE_EQ(none.trace.estimate[0].params.wheel_radius_left_m, 0.32);

  const auto [ref_pos, ref_th] = reference_dead_reckoning(track, in.nominal);
  EXPECT_NEAR(s.pose_rmse_m, ref_pos, 1e-9 + 1e-9 * ref_pos);
  EXPECT_NEAR(s.heading_rmse_rad, ref_th, 1e-9 + 1e-9 * ref_th);
  const TrackCalibrationScore fixed = score_fixed_params(in, in.nominal);
  EXPECT_DOUBLE_EQ(fixed.pose_rmse_m, s.pose_rmse_m);
  EXPECT_DOUBLE_EQ(fixed.v_rmse_m_s, s.v_rmse_m_s);

  // Nominal values are 1-2 % off: they never converge.
  EXPECT_FALSE(s.convergence_time_s.has_value());
  ASSERT_TRUE(s.truth_final.has_value());
  EXPECT_NEAR(s.truth_final->wheel_radius_right_m, truth.wheel_radius_right_m, 1e-12);

  const TrackCalibrationScore best = score_fixed_params(in, truth);
  const auto [true_pos, true_th] = reference_dead_reckoning(track, truth);
  EXPECT_NEAR(best.pose_rmse_m, true_pos, 1e-9 + 1e-9 * true_pos);
  EXPECT_LT(best.pose_rmse_m, 0.2 * s.pose_rmse_m);
  EXPECT_LT(best.heading_rmse_rad, 0.2 * s.heading_rmse_rad);
  EXPECT_LT(best.v_rmse_m_s, s.v_rmse_m_s);
  EXPECT_LT(best.w_rmse_rad_s, s.w_rmse_rad_s);
  // The odometry with the true parameters matches GT velocities to the
  // encoder quantisation over 10 ms (~0.01 m/s, ~0.02 rad/s).
  EXPECT_LT(best.v_rmse_m_s, 0.02);
  EXPECT_LT(best.w_rmse_rad_s, 0.04);
  // The truth itself is converged from the first sample (t = 0.1 s).
  ASSERT_TRUE(best.convergence_time_s.has_value());
  EXPECT_NEAR(*best.convergence_time_s, 0.1, 1e-9);
}

TEST(CalibrationScore, RadiusStepSplitsConvergence) {
  ChairTrackOptions o = testing_support::misaligned_chair(40.0, 5);
  o.effects.push_back("radius_step:t=20,scale_l=1.01,scale_r=0.985");
  const CalibrationInput in = build_calibration_input(chair_track(o), {});
  ASSERT_TRUE(in.truth.has_value());
  const OdometryParams before = chair_truth(kRunScaleL, kRunScaleR, kRunScaleBase);
  const OdometryParams after = chair_truth(kRunScaleL * 1.01, kRunScaleR * 0.985, kRunScaleBase);
  // Right before the step: converged at once, never re-converged after it.
  const TrackCalibrationScore s1 = score_fixed_params(in, before);
  ASSERT_TRUE(s1.convergence_time_s.has_value());
  EXPECT_NEAR(*s1.convergence_time_s, 0.1, 1e-9);
  ASSERT_EQ(s1.reconvergence_s.size(), 1u);
  EXPECT_FALSE(s1.reconvergence_s[0].has_value());
  // Right after the step: not converged before it, at once after it.
  const TrackCalibrationScore s2 = score_fixed_params(in, after);
  EXPECT_FALSE(s2.convergence_time_s.has_value());
  ASSERT_EQ(s2.reconvergence_s.size(), 1u);
  ASSERT_TRUE(s2.reconvergence_s[0].has_value());
  EXPECT_NEAR(*s2.reconvergence_s[0], 0.0, 1e-9);  // a sample falls at t = 20 s
  EXPECT_NEAR(s2.truth_final->wheel_radius_left_m, after.wheel_radius_left_m, 1e-12);
}

TEST(CalibrationRun, DualKfConvergesWithin120s) {
  const CalibrationInput& in = input_120();
  const OdometryParams truth = chair_truth(kRunScaleL, kRunScaleR, kRunScaleBase);
  CalibrationOptions o;
  o.method = CalibrationMethod::dkf;
  const CalibrationResult r = run_calibration({&in}, o);
  EXPECT_EQ(r.method, CalibrationMethod::dkf);
  EXPECT_EQ(r.iterations, static_cast<long>(in.samples.size()));
  ASSERT_EQ(r.trace.t.size(), in.samples.size());
  EXPECT_EQ(r.trace.t.front(), in.sample_t.front());
  EXPECT_EQ(r.trace.track.back(), 0);
  EXPECT_GE(r.ms_per_iteration, 0.0);
  EXPECT_EQ(r.mean_particles, 0.0);
  EXPECT_TRUE(within(r.final_params, truth, 0.005));
  ASSERT_EQ(r.tracks.size(), 1u);
  const TrackCalibrationScore& s = r.tracks[0];
  ASSERT_TRUE(s.convergence_time_s.has_value());
  EXPECT_GT(*s.convergence_time_s, 0.1);  // it starts from the nominal values
  EXPECT_LT(*s.convergence_time_s, in.t.back());
  // The trace agrees with the convergence time: both radii within from then
  // on (the wheel base is not part of convergence).
  for (std::size_t i = 0; i < r.trace.t.size(); ++i)
    if (r.trace.t[i] >= *s.convergence_time_s + in.t.front()) {
      OdometryParams radii = r.trace.estimate[i].params;
      radii.wheel_base_m = truth.wheel_base_m;
      ASSERT_TRUE(within(radii, truth, 0.005)) << r.trace.t[i];
    }
  const TrackCalibrationScore nominal = score_fixed_params(in, in.nominal);
  EXPECT_LT(s.pose_rmse_m, 0.5 * nominal.pose_rmse_m);
  EXPECT_LT(s.heading_rmse_rad, 0.5 * nominal.heading_rmse_rad);
}

// The adaptive PF (odotune/filters/pf_calibrator.h) gets within ~1 % in seconds and
// then wanders around the truth with its particle spread (~0.3 %), so on a
// 120 s track its "stays within 0.5 %" convergence is not reliably reached;
// checked instead: every estimate from 30 s on within 1.5 % (the nominal
// values are 1-2 % off), the mean estimate over the second half within 0.5 %
// for the radii (1 % for D, which the paper does not analyse and which the
// 10 ms encoder-rate quantisation biases by ~0.2 %), and the calibrated dead
// reckoning far better than the nominal one.
TEST(CalibrationRun, AdaptivePfApproachesTheTruth) {
  const CalibrationInput& in = input_120();
  const OdometryParams truth = chair_truth(kRunScaleL, kRunScaleR, kRunScaleBase);
  CalibrationOptions o;
  o.method = CalibrationMethod::adaptive_pf;
  o.pf.seed = 3;
  const CalibrationResult r = run_calibration({&in}, o);
  EXPECT_EQ(r.iterations, static_cast<long>(in.samples.size()));
  ASSERT_EQ(r.trace.estimate.size(), in.samples.size());
  EXPECT_EQ(r.trace.estimate.front().particles, 8000);  // the adaptive rule's initial count
  EXPECT_GT(r.mean_particles, 0.0);
  EXPECT_LT(r.mean_particles, 8000.0);  // and it adapted
  OdometryParams mean;
  int n = 0;
  for (std::size_t i = 0; i < r.trace.t.size(); ++i) {
    const OdometryParams& p = r.trace.estimate[i].params;
    if (r.trace.t[i] >= 30.0) {
      ASSERT_TRUE(within(p, truth, 0.015)) << "t = " << r.trace.t[i];
    }
    if (r.trace.t[i] < 0.5 * in.t.back()) continue;
    mean.wheel_radius_left_m += p.wheel_radius_left_m;
    mean.wheel_radius_right_m += p.wheel_radius_right_m;
    mean.wheel_base_m += p.wheel_base_m;
    ++n;
  }
  ASSERT_GT(n, 0);
  EXPECT_NEAR(mean.wheel_radius_left_m / n, truth.wheel_radius_left_m, 0.005 * truth.wheel_radius_left_m);
  EXPECT_NEAR(mean.wheel_radius_right_m / n, truth.wheel_radius_right_m, 0.005 * truth.wheel_radius_right_m);
  EXPECT_NEAR(mean.wheel_base_m / n, truth.wheel_base_m, 0.01 * truth.wheel_base_m);
  const TrackCalibrationScore nominal = score_fixed_params(in, in.nominal);
  EXPECT_LT(r.tracks[0].pose_rmse_m, 0.25 * nominal.pose_rmse_m);
  EXPECT_LT(r.tracks[0].heading_rmse_rad, 0.5 * nominal.heading_rmse_rad);
  // Seeded: the same run gives the same estimates.
  const CalibrationResult again = run_calibration({&in}, o);
  EXPECT_EQ(again.final_params.wheel_radius_right_m, r.final_params.wheel_radius_right_m);
  EXPECT_EQ(again.tracks[0].pose_rmse_m, r.tracks[0].pose_rmse_m);
}

TEST(CalibrationRun, BatchScoresAreThoseOfTheFittedConstants) {
  const CalibrationInput& in = input_120();
  CalibrationOptions o;
  o.method = CalibrationMethod::batch_velocity;
  const CalibrationResult r = run_calibration({&in}, o);
  EXPECT_TRUE(r.batch_converged);
  EXPECT_EQ(r.iterations, static_cast<long>(in.samples.size()));
  EXPECT_TRUE(within(r.final_params, chair_truth(kRunScaleL, kRunScaleR, kRunScaleBase), 0.005));
  ASSERT_EQ(r.trace.t.size(), 1u);
  EXPECT_GT(r.trace.estimate[0].sd_wheel_base_m, 0.0);
  const TrackCalibrationScore fixed = score_fixed_params(in, r.final_params);
  EXPECT_DOUBLE_EQ(r.tracks[0].pose_rmse_m, fixed.pose_rmse_m);
  EXPECT_DOUBLE_EQ(r.tracks[0].heading_rmse_rad, fixed.heading_rmse_rad);
  // The fitted constants are within the tolerance from the first sample, but an
  // offline fit reports no convergence time.
  ASSERT_TRUE(fixed.convergence_time_s.has_value());
  EXPECT_FALSE(r.tracks[0].convergence_time_s.has_value());
}

TEST(CalibrationRun, OnlineMethodsCarryTheFilterAcrossTracks) {
  const CalibrationInput& first = input_120();
  const CalibrationInput second = build_calibration_input(
      chair_track(testing_support::misaligned_chair(30.0, 22)), {});
  CalibrationOptions o;
  o.method = CalibrationMethod::dkf;
  const CalibrationResult both = run_calibration({&first, &second}, o);
  ASSERT_EQ(both.tracks.size(), 2u);
  EXPECT_EQ(both.iterations, static_cast<long>(first.samples.size() + second.samples.size()));
  EXPECT_EQ(both.trace.track.front(), 0);
  EXPECT_EQ(both.trace.track.back(), 1);
  // The second track starts from the first one's estimate: converged at once.
  const CalibrationResult alone = run_calibration({&first}, o);
  EXPECT_EQ(both.tracks[0].final_params.wheel_base_m, alone.final_params.wheel_base_m);
  ASSERT_TRUE(both.tracks[1].convergence_time_s.has_value());
  EXPECT_NEAR(*both.tracks[1].convergence_time_s, 0.1, 1e-9);
}

TEST(CalibrationRun, BadOptionsAndInputsThrow) {
  CalibrationOptions o;
  o.method = CalibrationMethod::none;
  EXPECT_THROW(run_calibration({}, o), std::invalid_argument);
  EXPECT_THROW(run_calibration({nullptr}, o), std::invalid_argument);
  o.convergence_tolerance = 2.0;
  EXPECT_THROW(run_calibration({&input_120()}, o), std::invalid_argument);
  EXPECT_THROW(score_fixed_params(input_120(), params(0.3, 0.3, 0.0)), std::invalid_argument);
}

}  // namespace
}  // namespace odotune::calibration

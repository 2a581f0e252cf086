// The reference's own jitter (odotune/calibration/reference_jitter.h) and the noise
// of velocities derived from it (calibration_input.h, --ext-from-gt): a
// simulated ground truth with known white noise is read back within 15 %,
// an exact one as (nearly) none, and the derived samples carry the
// variances 2σ²/T² (+ the encoders' quantisation).
#include <cmath>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/reference_jitter.h>
#include <odotune/objectives/track_samples.h>

#include "support/calibration_track.h"

namespace odotune::calibration {
namespace {

using ::testing::HasSubstr;
using testing_support::chair_scenario;
using testing_support::ChairTrackOptions;

tracks::Track noisy_chair(double sigma_m, double sigma_rad) {
  ChairTrackOptions o;
  o.duration_s = 60.0;
  o.seed = 41;
  o.ext = false;
  sim::Scenario sc = chair_scenario(o);
  sc.sensors.ground_truth.sigma_m = sigma_m;
  sc.sensors.ground_truth.sigma_rad = sigma_rad;
  return sim::simulate(sc);
}

TEST(ReferenceJitter, ReadsBackTheSimulatedNoise) {
  const ReferenceJitter j = estimate_reference_jitter(
      objectives::ground_truth_series(noisy_chair(0.002, 0.004)));
  EXPECT_GT(j.triples, 5000u);
  EXPECT_NEAR(j.sigma_xy_m, 0.002, 0.15 * 0.002);
  EXPECT_NEAR(j.sigma_theta_rad, 0.004, 0.15 * 0.004);
  EXPECT_NEAR(j.median_dt_s, 0.01, 1e-9);
}

TEST(ReferenceJitter, AnExactReferenceHasAlmostNone) {
  const ReferenceJitter j = estimate_reference_jitter(objectives::ground_truth_series(noisy_chair(0.0, 0.0)));
  // Only the motion's own a·Δt² (and the 1e-5 m rounding) remain.
  EXPECT_LT(j.sigma_xy_m, 5e-5);
  EXPECT_LT(j.sigma_theta_rad, 1e-4);
  EXPECT_EQ(estimate_reference_jitter(objectives::PoseSeries{}).triples, 0u);
}

TEST(ReferenceJitter, DerivedVelocitiesCarryTheEstimatedNoise) {
  const tracks::Track track = noisy_chair(0.002, 0.004);
  CalibrationInputOptions o;
  o.ext_from_gt_rate_hz = 10.0;
  const CalibrationInput in = build_calibration_input(track, o);
  ASSERT_FALSE(in.samples.empty());
  const ReferenceJitter j = estimate_reference_jitter(objectives::ground_truth_series(track));
  const double period = 0.1;
  const double q = 2.0 * std::numbers::pi / 8800.0 / o.wheel_rate_window_s;  // chair encoders
  const double var_omega = q * q / 6.0;
  const double expect_v = 2.0 * j.sigma_xy_m * j.sigma_xy_m / (period * period) + 0.32 * 0.32 * var_omega / 2.0;
  const double expect_w = 2.0 * j.sigma_theta_rad * j.sigma_theta_rad / (period * period) +
                          2.0 * 0.32 * 0.32 * var_omega / (0.65 * 0.65);
  EXPECT_NEAR(in.samples.front().v_var, expect_v, 1e-12 * expect_v);
  EXPECT_NEAR(in.samples.back().w_var, expect_w, 1e-12 * expect_w);
  EXPECT_NEAR(in.ext_sigma_v_m_s, std::sqrt(expect_v), 1e-12);
  EXPECT_THAT(in.ext_noise, HasSubstr("jitter"));
  // And it is the noise the derived velocities really have: their spread
  // about the true body velocity (the exact ground truth's) is within 25 %.
  const CalibrationInput exact = build_calibration_input(noisy_chair(0.0, 0.0), o);
  ASSERT_EQ(exact.samples.size(), in.samples.size());
  double ss_v = 0.0, ss_w = 0.0;
  for (std::size_t i = 0; i < in.samples.size(); ++i) {
    ss_v += std::pow(in.samples[i].v_m_s - exact.samples[i].v_m_s, 2);
    ss_w += std::pow(in.samples[i].w_rad_s - exact.samples[i].w_rad_s, 2);
  }
  const double n = static_cast<double>(in.samples.size());
  EXPECT_NEAR(std::sqrt(ss_v / n), std::sqrt(2.0) * 0.002 / period, 0.25 * std::sqrt(2.0) * 0.002 / period);
  EXPECT_NEAR(std::sqrt(ss_w / n), std::sqrt(2.0) * 0.004 / period, 0.25 * std::sqrt(2.0) * 0.004 / period);
}

}  // namespace
}  // namespace odotune::calibration

// Offline batch calibration (odotune/calibration/batch_calibration.h): on
// simulated wheelchair tracks with known radius and wheel-base errors the
// least-squares fit recovers the truth within the paper's 0.5 %, its standard
// errors cover the actual error and shrink with more data, and gross outliers
// in the external velocities do not move it (Huber loss).
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/calibration/batch_calibration.h>
#include <odotune/calibration/calibration_input.h>

#include "support/calibration_track.h"

namespace odotune::calibration {
namespace {

using ::testing::HasSubstr;
using testing_support::chair_track;
using testing_support::chair_truth;
using testing_support::ChairTrackOptions;

constexpr double kScaleL = 0.99, kScaleR = 1.012, kScaleBase = 1.02;

CalibrationInput chair_input(std::uint64_t seed, double duration_s = 120.0) {
  ChairTrackOptions o;
  o.duration_s = duration_s;
  o.seed = seed;
  o.effects = {"radius_error:scale_l=0.99,scale_r=1.012", "wheel_base_error:scale=1.02"};
  return build_calibration_input(chair_track(o), {});
}

const CalibrationInput& input_a() {
  static const CalibrationInput in = chair_input(11);
  return in;
}
const CalibrationInput& input_b() {
  static const CalibrationInput in = chair_input(12);
  return in;
}

void expect_within(const filters::OdometryParams& got, const filters::OdometryParams& truth, double rel_tol) {
  EXPECT_NEAR(got.wheel_radius_left_m, truth.wheel_radius_left_m, rel_tol * truth.wheel_radius_left_m);
  EXPECT_NEAR(got.wheel_radius_right_m, truth.wheel_radius_right_m, rel_tol * truth.wheel_radius_right_m);
  EXPECT_NEAR(got.wheel_base_m, truth.wheel_base_m, rel_tol * truth.wheel_base_m);
}

TEST(BatchCalibration, RecoversRadiiAndWheelBaseWithSensibleSds) {
  const filters::OdometryParams truth = chair_truth(kScaleL, kScaleR, kScaleBase);
  const CalibrationInput& in = input_a();
  const BatchCalibrationSummary fit = batch_calibrate({&in}, in.nominal);
  EXPECT_TRUE(fit.converged) << fit.termination;
  EXPECT_EQ(fit.residual_pairs, static_cast<long>(in.samples.size()));
  expect_within(fit.params, truth, 0.005);
  // The nominal start is 1-2 % off: the fit really moved.
  EXPECT_GT(std::abs(fit.params.wheel_base_m - in.nominal.wheel_base_m), 0.01);

  // Standard errors: finite, positive, small against the values, and the
  // actual errors lie within a few of them.
  const double sds[] = {fit.sd_radius_left_m, fit.sd_radius_right_m, fit.sd_wheel_base_m};
  const double errs[] = {fit.params.wheel_radius_left_m - truth.wheel_radius_left_m,
                         fit.params.wheel_radius_right_m - truth.wheel_radius_right_m,
                         fit.params.wheel_base_m - truth.wheel_base_m};
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(std::isfinite(sds[i])) << i;
    EXPECT_GT(sds[i], 1e-6) << i;
    EXPECT_LT(sds[i], 0.002 * (i == 2 ? truth.wheel_base_m : 0.32)) << i;  // < 0.2 %
    EXPECT_LT(std::abs(errs[i]), 5.0 * sds[i] + 1e-4) << i;
  }
}

TEST(BatchCalibration, MoreTracksShrinkTheStandardErrors) {
  const CalibrationInput& a = input_a();
  const CalibrationInput& b = input_b();
  const BatchCalibrationSummary one = batch_calibrate({&a}, a.nominal);
  const BatchCalibrationSummary two = batch_calibrate({&a, &b}, a.nominal);
  EXPECT_EQ(two.residual_pairs, one.residual_pairs + static_cast<long>(b.samples.size()));
  expect_within(two.params, chair_truth(kScaleL, kScaleR, kScaleBase), 0.005);
  // Twice the data: sd × ~1/√2 (allow 0.55..0.9).
  for (auto [s1, s2] : {std::pair{one.sd_radius_left_m, two.sd_radius_left_m},
                        std::pair{one.sd_radius_right_m, two.sd_radius_right_m},
                        std::pair{one.sd_wheel_base_m, two.sd_wheel_base_m}}) {
    EXPECT_GT(s2, 0.55 * s1);
    EXPECT_LT(s2, 0.9 * s1);
  }
}

TEST(BatchCalibration, HuberLossResistsGrossOutliers) {
  CalibrationInput in = input_a();
  // Every 25th measurement 1 m/s and 1 rad/s off (50 σ), alternating in sign
  // (Huber bounds each outlier's pull to 3 σ, it does not remove it, so 4 %
  // one-signed outliers would still bias the fit by ~0.5 %).
  double sign = 1.0;
  for (std::size_t i = 0; i < in.samples.size(); i += 25, sign = -sign) {
    in.samples[i].v_m_s += sign;
    in.samples[i].w_rad_s -= sign;
  }
  const BatchCalibrationSummary fit = batch_calibrate({&in}, in.nominal);
  expect_within(fit.params, chair_truth(kScaleL, kScaleR, kScaleBase), 0.005);
  // And the fit stays close to the clean one (within ~1 sd).
  const BatchCalibrationSummary clean = batch_calibrate({&input_a()}, in.nominal);
  EXPECT_NEAR(fit.params.wheel_base_m, clean.params.wheel_base_m, 1.5 * clean.sd_wheel_base_m);
  EXPECT_NEAR(fit.params.wheel_radius_left_m, clean.params.wheel_radius_left_m, 1.5 * clean.sd_radius_left_m);
}

TEST(BatchCalibration, NoSamplesOrBadStartThrow) {
  CalibrationInput empty;
  empty.track_name = "empty_track";
  empty.nominal = input_a().nominal;
  try {
    batch_calibrate({&empty}, empty.nominal);
    FAIL() << "no samples must throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("'empty_track'"));
  }
  filters::OdometryParams bad = input_a().nominal;
  bad.wheel_base_m = -1.0;
  EXPECT_THROW(batch_calibrate({&input_a()}, bad), std::invalid_argument);
  EXPECT_THROW(batch_calibrate({nullptr}, input_a().nominal), std::invalid_argument);
}

}  // namespace
}  // namespace odotune::calibration

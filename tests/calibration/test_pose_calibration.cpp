// Pose-domain batch calibration (odotune/calibration/pose_calibration.h) on simulated
// wheelchair tracks with known radius and wheel-base errors: from ticks and
// ground truth, from ticks and sparse position fixes only, by segments, with
// a wrong start heading, and its refusals.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/pose_calibration.h>

#include "support/calibration_track.h"

namespace odotune::calibration {
namespace {

using ::testing::HasSubstr;
using filters::OdometryParams;
using testing_support::chair_scenario;
using testing_support::chair_truth;
using testing_support::ChairTrackOptions;

constexpr double kPoseScaleL = testing_support::kMisalignedScaleL,
                 kPoseScaleR = testing_support::kMisalignedScaleR,
                 kPoseScaleBase = testing_support::kMisalignedScaleBase;

double worst_relative_error(const OdometryParams& p, const OdometryParams& truth) {
  return std::max({std::abs(p.wheel_radius_left_m / truth.wheel_radius_left_m - 1.0),
                   std::abs(p.wheel_radius_right_m / truth.wheel_radius_right_m - 1.0),
                   std::abs(p.wheel_base_m / truth.wheel_base_m - 1.0)});
}

CalibrationInput pose_input(const tracks::Track& track) {
  CalibrationInputOptions o;
  o.require_velocity_samples = false;
  return build_calibration_input(track, o);
}

TEST(PoseCalibration, GroundTruthWholeRunRecoversTheGeometry) {
  const tracks::Track track = testing_support::chair_track(testing_support::misaligned_chair(120.0, 31));
  const CalibrationInput in = build_calibration_input(track, {});
  const PoseCalibrationSummary s = pose_calibrate({&in}, in.nominal);
  const OdometryParams truth = chair_truth(kPoseScaleL, kPoseScaleR, kPoseScaleBase);
  EXPECT_TRUE(s.converged) << s.termination;
  EXPECT_LT(worst_relative_error(s.params, truth), 0.002);
  EXPECT_LT(worst_relative_error(in.nominal, truth), 0.03);  // the fit had work to do
  EXPECT_EQ(s.segments, 1);
  EXPECT_EQ(s.ground_truth_runs, 1);
  EXPECT_EQ(s.fix_runs, 0);
  EXPECT_LT(s.final_rmse_m, 0.1 * s.initial_rmse_m);
  EXPECT_THAT(s.residuals, HasSubstr("ground truth"));
  EXPECT_THAT(s.residuals, HasSubstr("whole-run"));
  // Standard errors: finite, positive and covering the truth within 5 sd
  // (they are optimistic on whole runs, header).
  for (double sd : {s.sd_radius_left_m, s.sd_radius_right_m, s.sd_wheel_base_m}) {
    EXPECT_TRUE(std::isfinite(sd));
    EXPECT_GT(sd, 0.0);
  }
}

TEST(PoseCalibration, TicksAndSparseFixesRecoverTheGeometryWithinAFifthOfAPercent) {
  ChairTrackOptions o = testing_support::misaligned_chair(600.0, 32);
  o.gt = false;
  o.ext = false;
  sim::Scenario sc = chair_scenario(o);
  sc.sensors.aps.enabled = true;
  sc.sensors.aps.rate_hz = 1.0;
  sc.sensors.aps.sigma_m = 0.02;
  const tracks::Track track = sim::simulate(sc);
  ASSERT_FALSE(track.has_gt());
  ASSERT_FALSE(track.has(tracks::Col::v_ext));
  const CalibrationInput in = pose_input(track);
  EXPECT_TRUE(in.samples.empty());
  ASSERT_GT(in.fix_t.size(), 500u);

  PoseCalibrationOptions po;
  po.segment_s = 60.0;  // a fitted start pose per minute of fixes
  const PoseCalibrationSummary s = pose_calibrate({&in}, in.nominal, po);
  EXPECT_TRUE(s.converged) << s.termination;
  EXPECT_EQ(s.fix_runs, 1);
  EXPECT_EQ(s.ground_truth_runs, 0);
  EXPECT_GE(s.segments, 9);
  EXPECT_THAT(s.residuals, HasSubstr("position fixes"));
  const OdometryParams truth = chair_truth(kPoseScaleL, kPoseScaleR, kPoseScaleBase);
  EXPECT_LT(worst_relative_error(s.params, truth), 0.002)
      << s.params.wheel_radius_left_m << " " << s.params.wheel_radius_right_m << " " << s.params.wheel_base_m;
  // The fit's residual is the fixes' own noise (σ 0.02 m per axis).
  EXPECT_LT(s.final_rmse_m, 0.04);
}

TEST(PoseCalibration, SegmentsCutTheRunAndStillRecoverTheGeometry) {
  const tracks::Track track = testing_support::chair_track(testing_support::misaligned_chair(120.0, 33));
  const CalibrationInput in = build_calibration_input(track, {});
  PoseCalibrationOptions po;
  po.segment_s = 20.0;
  const PoseCalibrationSummary s = pose_calibrate({&in}, in.nominal, po);
  // Abutting 20 s segments over the run (the simulator finishes its lap,
  // so the run is longer than the 120 s asked for).
  EXPECT_EQ(s.segments, static_cast<long>(std::ceil((in.t.back() - in.t.front()) / 20.0))) << s.residuals;
  EXPECT_THAT(s.residuals, HasSubstr("segments of 20 s"));
  EXPECT_LT(worst_relative_error(s.params, chair_truth(kPoseScaleL, kPoseScaleR, kPoseScaleBase)), 0.002);
}

TEST(PoseCalibration, FittedStartHeadingAbsorbsAWrongReferenceHeading) {
  // The first ground-truth heading is off by 0.05 rad (a mis-set mocap
  // frame): held fixed it biases the wheel base; fitted, it does not.
  tracks::TrackData d = testing_support::chair_track(testing_support::misaligned_chair(120.0, 34)).data();
  std::vector<double>& th = d.col(tracks::Col::gt_theta);
  th[0] += 0.05;
  const tracks::Track track(std::move(d));
  const CalibrationInput in = build_calibration_input(track, {});
  const OdometryParams truth = chair_truth(kPoseScaleL, kPoseScaleR, kPoseScaleBase);
  PoseCalibrationOptions po;
  const double fixed = worst_relative_error(pose_calibrate({&in}, in.nominal, po).params, truth);
  po.fit_start_heading = true;
  const PoseCalibrationSummary s = pose_calibrate({&in}, in.nominal, po);
  EXPECT_THAT(s.residuals, HasSubstr("start heading fitted"));
  EXPECT_LT(worst_relative_error(s.params, truth), 0.002);
  EXPECT_GT(fixed, 2.0 * worst_relative_error(s.params, truth));
}

TEST(PoseCalibration, RefusesARunWithoutReferenceAndBadOptions) {
  ChairTrackOptions o = testing_support::misaligned_chair(30.0, 35);
  o.gt = false;
  sim::Scenario sc = chair_scenario(o);
  sc.sensors.aps.enabled = false;
  const tracks::Track track = sim::simulate(sc);
  const CalibrationInput in = build_calibration_input(track, {});  // has v_ext
  try {
    pose_calibrate({&in}, in.nominal);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("track 'chair'"));
    EXPECT_THAT(e.what(), HasSubstr("no reference"));
  }
  PoseCalibrationOptions bad;
  bad.segment_s = -1.0;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("segment_s"));
  bad = {};
  bad.loss_scale_m = 0.0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("loss_scale_m"));
  EXPECT_THROW(pose_calibrate({}, in.nominal), std::invalid_argument);
  EXPECT_THROW(pose_calibrate({nullptr}, in.nominal), std::invalid_argument);
}

}  // namespace
}  // namespace odotune::calibration

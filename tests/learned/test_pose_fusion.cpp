// Odometry fused with position fixes (odotune/learned/pose_fusion.h), the slip
// detector without motor power (odotune/learned/slip_detector.h: drives commands
// and none), and the fusion input's reference velocities from the ground
// truth and its slices (odotune/learned/fusion_input.h), on simulated chair drives.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/learned/fusion_input.h>
#include <odotune/learned/learned_odometry.h>
#include <odotune/learned/odometry_metrics.h>
#include <odotune/learned/pose_fusion.h>
#include <odotune/learned/slip_detector.h>

#include "support/calibration_track.h"

namespace odotune::learned {
namespace {

using testing_support::ChairTrackOptions;

// A chair drive with unequal tyres and 1 Hz fixes (σ 5 cm, without
// variances in the track), laid out at 10 Hz.
FusionInput fixed_chair(std::uint64_t seed, double duration_s = 120.0) {
  ChairTrackOptions o;
  o.duration_s = duration_s;
  o.seed = seed;
  o.effects = {"radius_error:scale_l=0.98,scale_r=1.01"};
  sim::Scenario sc = testing_support::chair_scenario(o);
  sc.sensors.aps.enabled = true;
  sc.sensors.aps.rate_hz = 1.0;
  sc.sensors.aps.sigma_m = 0.05;
  return build_fusion_input(sim::simulate(sc));
}

std::vector<OdometryMeasurement> kinematic_measurements(const FusionInput& in) {
  return static_odometry(in, 1e-4, 1e-3);
}

TEST(PoseFusion, FixesKeepTheFusedPathNearTheTruth) {
  const FusionInput in = fixed_chair(3);
  ASSERT_TRUE(in.has_fixes);
  PoseFusionOptions o;
  o.fix_sigma_m = 0.05;
  o.noise.use_external = false;
  const PoseFusionTrace t = replay_pose_fusion(in, kinematic_measurements(in), o);
  ASSERT_TRUE(t.healthy);
  EXPECT_GT(t.fixes, 100u);
  const objectives::ErrorMetrics fused = pose_fusion_errors(in, t);
  const double dead = dead_reckoning_errors(in, in.v_kin, in.w_kin, 0.0).rmse();
  EXPECT_LT(fused.rmse_m, 0.1);
  EXPECT_LT(fused.rmse_m, 0.25 * dead) << "dead reckoning " << dead;
  // Without a fix σ, fixes without variances are refused by name.
  o.fix_sigma_m = 0.0;
  try {
    replay_pose_fusion(in, kinematic_measurements(in), o);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--fix-sigma-m"), std::string::npos) << e.what();
  }
  // A track without fixes has nothing to fuse.
  FusionInput none = in;
  none.has_fixes = false;
  EXPECT_THROW(replay_pose_fusion(none, kinematic_measurements(in), o), std::invalid_argument);
}

// External velocities from the ground truth at 10 Hz land one per step and
// follow the true velocities; a slice keeps its steps' values.
TEST(FusionInput, ReferenceVelocitiesFromTheGroundTruthAndSlices) {
  ChairTrackOptions c;
  c.duration_s = 60;
  c.ext = false;
  const tracks::Track track = testing_support::chair_track(c);
  FusionInputOptions o;
  o.ext_from_gt_hz = 10.0;
  const FusionInput in = build_fusion_input(track, o);
  ASSERT_TRUE(in.has_ext);
  double err = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 2; k < in.size(); ++k)
    if (std::isfinite(in.v_ext[k]) && std::isfinite(in.v_true[k]))
      err += std::abs(in.v_ext[k] - in.v_true[k]), ++n;
  EXPECT_GT(n, in.size() * 9 / 10);
  EXPECT_LT(err / static_cast<double>(n), 0.02);
  const FusionInput part = slice_fusion_input(in, 100, 300);
  ASSERT_EQ(part.size(), 200u);
  EXPECT_EQ(part.t.front(), in.t[100]);
  EXPECT_EQ(part.v_kin[7], in.v_kin[107]);
  EXPECT_TRUE(part.has_gt);
  FusionInputOptions bad;
  bad.ext_from_gt_hz = 1000.0;
  EXPECT_THROW(build_fusion_input(track, bad), std::invalid_argument);
}

// Without motor power the detector reads the commands beside the wheels, or
// nothing but the odometry; either trains, runs and sets flag thresholds.
TEST(SlipDetector, TrainsWithoutMotorPower) {
  const FusionInput a = fixed_chair(5, 60.0), b = fixed_chair(6, 60.0);
  ASSERT_FALSE(a.has_power);
  ASSERT_TRUE(a.has_cmd);
  EXPECT_EQ(available_slip_drive({&a, &b}), SlipDrive::commands);
  for (SlipDrive drive : {SlipDrive::commands, SlipDrive::none}) {
    SlipTrainingOptions o;
    o.drive = drive;
    o.training.max_iterations = 5;
    o.stride = 8;
    const SlipDetectorModel d = train_slip_detector({&a, &b}, {kinematic_odometry(a), kinematic_odometry(b)}, o,
                                                    nullptr);
    EXPECT_EQ(d.drive, drive);
    EXPECT_EQ(d.input, tracks::OdometryInput::wheels);
    EXPECT_GT(d.flag_var_v, 0.0);
    EXPECT_GE(d.flag_var_v, d.floor_var_v);
    SlipDetectorStepper s(&d);
    for (std::size_t k = 1; k < a.size(); ++k) {
      const auto var = s.step(a, k);
      ASSERT_TRUE(std::isfinite(var[0]) && std::isfinite(var[1])) << k;
    }
  }
  SlipTrainingOptions power;
  power.drive = SlipDrive::power;
  EXPECT_THROW(train_slip_detector({&a}, {kinematic_odometry(a)}, power, nullptr), std::invalid_argument);
  SlipDrive d{};
  EXPECT_TRUE(parse_slip_drive("none", &d));
  EXPECT_EQ(d, SlipDrive::none);
}

}  // namespace
}  // namespace odotune::learned

// The calibration of a body-velocity odometry (odotune/calibration/twist_calibration.h):
// on a drive whose motion is its commands scaled and delayed, the fit finds
// the scales and the delay from the ground truth, and the scales from 1 Hz
// fixes alone; a measured twist gets no delay; bad inputs are one-line errors.
#include <cmath>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <odotune/calibration/twist_calibration.h>
#include <odotune/tracks/body_velocity.h>

namespace odotune::calibration {
namespace {

// Commands at 20 Hz changing every 2 s (a smooth random tour), the robot's
// motion v = 0.9·v_cmd(t − 0.3), w = 1.1·w_cmd(t − 0.3), ground truth at
// 50 Hz (or fixes at 1 Hz, without ground truth).
tracks::Track twist_drive(tracks::BodyVelocitySource source, bool fixes_only, double delay_s = 0.3) {
  tracks::TrackData d;
  d.meta.name = fixes_only ? "fixes" : "drive";
  d.meta.body_velocity = source;
  const double duration = 240.0, step = 0.02;
  const auto n = static_cast<std::size_t>(duration / step) + 1;
  for (std::size_t i = 0; i < n; ++i) d.t.push_back(static_cast<double>(i) * step);
  auto& v = d.ensure(tracks::Col::v_cmd);
  auto& w = d.ensure(tracks::Col::w_cmd);
  for (std::size_t i = 0; i < n; i += 2) {  // 20 Hz commands, held between
    const double seg = std::floor(d.t[i] / 2.0);
    v[i] = 0.3 + 0.2 * std::sin(1.7 * seg);
    w[i] = 0.6 * std::sin(2.3 * seg + 0.4);
  }
  const tracks::Track commands(d);
  const tracks::BodyVelocityIntegral body(commands);
  double x = 0, y = 0, h = 0;
  auto& gx = d.ensure(fixes_only ? tracks::Col::aps_x : tracks::Col::gt_x);
  auto& gy = d.ensure(fixes_only ? tracks::Col::aps_y : tracks::Col::gt_y);
  if (!fixes_only) d.ensure(tracks::Col::gt_theta);
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) {
      const auto m = body.mean(d.t[i - 1], d.t[i], delay_s);
      const double ds = 0.9 * m[0] * step, dth = 1.1 * m[1] * step;
      x += ds * std::cos(h + 0.5 * dth);
      y += ds * std::sin(h + 0.5 * dth);
      h += dth;
    }
    if (fixes_only && i % 50 != 0) continue;
    gx[i] = x;
    gy[i] = y;
    if (!fixes_only) d.col(tracks::Col::gt_theta)[i] = h;
  }
  return tracks::Track(std::move(d));
}

TEST(TwistCalibration, CommandsGiveScalesAndDelayFromGroundTruth) {
  const tracks::Track t = twist_drive(tracks::BodyVelocitySource::commanded, false);
  const TwistCalibrationSummary s = calibrate_twist({&t}, tracks::OdometryInput::commands);
  EXPECT_NEAR(s.params.scale_v, 0.9, 0.005);
  EXPECT_NEAR(s.params.scale_w, 1.1, 0.005);
  EXPECT_NEAR(s.params.delay_s, 0.3, 0.011);
  EXPECT_LT(s.final_rmse_m, 0.1 * s.initial_rmse_m);
  EXPECT_EQ(s.ground_truth_runs, 1);
  EXPECT_GT(s.reference_points, 1000);
  EXPECT_TRUE(std::isfinite(s.sd_scale_v));
  EXPECT_NE(s.residuals.find("delay searched"), std::string::npos) << s.residuals;
  // Dead reckoning with the fit beats the commands as recorded.
  const TwistScore raw = score_twist(t, {}), cal = score_twist(t, s.params);
  EXPECT_LT(cal.pose_rmse_m, 0.2 * raw.pose_rmse_m);
  EXPECT_LT(cal.heading_rmse_rad, 0.2 * raw.heading_rmse_rad);
  EXPECT_GT(cal.samples, 10000u);
}

TEST(TwistCalibration, FixesAloneGiveTheScales) {
  const tracks::Track t = twist_drive(tracks::BodyVelocitySource::measured, true, 0.0);
  const TwistCalibrationSummary s = calibrate_twist({&t}, tracks::OdometryInput::twist);
  EXPECT_EQ(s.params.delay_s, 0.0);  // a measured twist has no delay to fit
  EXPECT_NEAR(s.params.scale_v, 0.9, 0.01);
  EXPECT_NEAR(s.params.scale_w, 1.1, 0.01);
  EXPECT_EQ(s.fix_runs, 1);
  EXPECT_EQ(s.ground_truth_runs, 0);
}

TEST(TwistCalibration, BadInputsAreOneLineErrors) {
  const tracks::Track t = twist_drive(tracks::BodyVelocitySource::commanded, false);
  EXPECT_THROW(calibrate_twist({&t}, tracks::OdometryInput::wheels), std::invalid_argument);
  EXPECT_THROW(calibrate_twist({}, tracks::OdometryInput::commands), std::invalid_argument);
  TwistCalibrationOptions o;
  o.fine_delay_step_s = 1.0;  // coarser than the coarse grid
  try {
    calibrate_twist({&t}, tracks::OdometryInput::commands, o);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fine_delay_step_s"), std::string::npos) << e.what();
  }
  tracks::TrackData d = t.data();
  d.meta.name = "blind";
  d.col(tracks::Col::gt_x).clear();
  d.col(tracks::Col::gt_y).clear();
  d.col(tracks::Col::gt_theta).clear();
  const tracks::Track blind(std::move(d));
  try {
    calibrate_twist({&blind}, tracks::OdometryInput::commands);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("track 'blind'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace odotune::calibration

// build_diag_input (odotune/diagnose/diag_input.h): odometry from ticks, wheel
// rates or commands; gyro; ground truth or fixes as reference; the reference
// sigma from metadata or estimated; never sim.effects; one-line errors.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/diagnose/diag_input.h>
#include <odotune/tracks/importers.h>

#include "diagnose/sim_track.h"

namespace odotune::diagnose {
namespace {

using testing_support::SimTrackOptions;
using testing_support::simulate_track;
using ::testing::HasSubstr;

SimTrackOptions short_run() {
  SimTrackOptions o;
  o.duration_s = 40.0;
  o.effects = {"radius_error:scale_l=0.99"};
  return o;
}

void drop_meta(tracks::TrackData& d, const std::string& key) {
  std::erase_if(d.meta.extra, [&](const auto& kv) { return kv.first == key; });
}

TEST(DiagInput, WheelTicksCommandsGyroAndGroundTruth) {
  const tracks::Track tr = simulate_track(short_run());
  const DiagInput in = build_diag_input(tr);
  EXPECT_EQ(in.track_name, "sim_track");
  EXPECT_EQ(in.odometry, OdometryKind::wheel_angles);
  EXPECT_EQ(in.radius_l_m, 0.08);
  EXPECT_EQ(in.wheel_base_m, 0.42);
  ASSERT_EQ(in.odo_t_s.size(), tr.size());  // every row holds ticks at 100 Hz
  const double per_tick = 2 * std::numbers::pi / 2048;
  for (std::size_t i = 0; i < tr.size(); i += 97) {
    EXPECT_DOUBLE_EQ(in.phi_l_rad[i], static_cast<double>(tr.ticks_l()[i] - tr.ticks_l()[0]) * per_tick);
    EXPECT_DOUBLE_EQ(in.phi_r_rad[i], static_cast<double>(tr.ticks_r()[i] - tr.ticks_r()[0]) * per_tick);
    EXPECT_EQ(in.cmd_v_mps[i], tr.col(tracks::Col::v_cmd)[i]);
    EXPECT_EQ(in.cmd_w_radps[i], tr.col(tracks::Col::w_cmd)[i]);
  }
  EXPECT_GT(in.phi_r_rad.back(), 100.0);  // the robot moved
  EXPECT_TRUE(in.v_mps.empty());
  EXPECT_EQ(in.gyro_t_s.size(), tr.size());
  EXPECT_EQ(in.reference, ReferenceKind::gt);
  ASSERT_EQ(in.ref_t_s.size(), tr.size());
  EXPECT_TRUE(in.has_ref_heading());
  EXPECT_EQ(in.ref_theta_rad[500], tr.col(tracks::Col::gt_theta)[500]);
  // sim.gt_sigma_m = 0 (noise-free ground truth): floored at 1 mm / 1 mrad.
  EXPECT_EQ(in.ref_sigma_m, 1e-3);
  EXPECT_EQ(in.ref_sigma_rad, 1e-3);
}

TEST(DiagInput, WheelRatesAreIntegratedLikeTheTicks) {
  SimTrackOptions o = short_run();
  o.omega = true;
  const tracks::Track with_ticks = simulate_track(o);
  tracks::TrackData d = with_ticks.data();
  d.ticks_l.clear();
  d.ticks_r.clear();
  const DiagInput from_rates = build_diag_input(tracks::Track(std::move(d)));
  const DiagInput from_ticks = build_diag_input(with_ticks);
  ASSERT_EQ(from_rates.odo_t_s, from_ticks.odo_t_s);
  double worst = 0.0;
  for (std::size_t i = 0; i < from_rates.odo_t_s.size(); ++i)
    worst = std::max({worst, std::abs(from_rates.phi_l_rad[i] - from_ticks.phi_l_rad[i]),
                      std::abs(from_rates.phi_r_rad[i] - from_ticks.phi_r_rad[i])});
  // A few counts (3 mrad each) of quantisation plus the rate resolution.
  EXPECT_LT(worst, 0.02);
  EXPECT_GT(from_rates.phi_l_rad.back(), 100.0);
}

TEST(DiagInput, CommandsAloneAreBodyVelocityOdometry) {
  SimTrackOptions o = short_run();
  o.encoders = false;
  const tracks::Track tr = simulate_track(o);
  const DiagInput in = build_diag_input(tr);
  EXPECT_EQ(in.odometry, OdometryKind::body_velocity);
  ASSERT_EQ(in.v_mps.size(), tr.size());
  EXPECT_EQ(in.v_mps[700], tr.col(tracks::Col::v_cmd)[700]);
  EXPECT_EQ(in.w_radps[700], tr.col(tracks::Col::w_cmd)[700]);
  EXPECT_TRUE(in.phi_l_rad.empty());
  EXPECT_TRUE(in.cmd_v_mps.empty());
  EXPECT_EQ(in.wheel_base_m, 0.42);  // kept from the metadata
}

TEST(DiagInput, FixesAsReferenceWithStatedOrEstimatedSigma) {
  SimTrackOptions o = short_run();
  o.duration_s = 150.0;
  o.gt_rate_hz = 0.0;
  o.aps_rate_hz = 2.0;
  o.aps_sigma_m = 0.04;
  const tracks::Track tr = simulate_track(o);
  const DiagInput in = build_diag_input(tr);
  EXPECT_EQ(in.reference, ReferenceKind::aps);
  EXPECT_FALSE(in.has_ref_heading());
  EXPECT_TRUE(std::isnan(in.ref_sigma_rad));
  EXPECT_EQ(in.ref_sigma_m, 0.04);
  EXPECT_NEAR(static_cast<double>(in.ref_t_s.size()), 2.0 * tr.duration_s(), 2.0);

  tracks::TrackData d = tr.data();
  drop_meta(d, "sim.aps_sigma_m");
  const DiagInput est = build_diag_input(tracks::Track(std::move(d)));
  EXPECT_GT(est.ref_sigma_m, 0.7 * 0.04);
  EXPECT_LT(est.ref_sigma_m, 1.4 * 0.04);
}

TEST(DiagInput, GroundTruthWithoutHeadingOrWrapped) {
  const tracks::Track tr = simulate_track(short_run());
  const DiagInput base = build_diag_input(tr);

  tracks::TrackData no_theta = tr.data();
  no_theta.col(tracks::Col::gt_theta).clear();
  const DiagInput a = build_diag_input(tracks::Track(std::move(no_theta)));
  EXPECT_EQ(a.reference, ReferenceKind::gt);
  EXPECT_FALSE(a.has_ref_heading());
  EXPECT_TRUE(std::isnan(a.ref_sigma_rad));
  EXPECT_EQ(a.ref_x_m, base.ref_x_m);

  tracks::TrackData wrapped = tr.data();
  for (double& th : wrapped.col(tracks::Col::gt_theta)) th = std::atan2(std::sin(th), std::cos(th));
  const DiagInput b = build_diag_input(tracks::Track(std::move(wrapped)));
  ASSERT_EQ(b.ref_theta_rad.size(), base.ref_theta_rad.size());
  double max_th = 0.0;
  for (double th : base.ref_theta_rad) max_th = std::max(max_th, std::abs(th));
  EXPECT_GT(max_th, 1.2 * std::numbers::pi);  // wrapping really happened
  for (std::size_t i = 0; i < b.ref_theta_rad.size(); i += 13)
    ASSERT_NEAR(b.ref_theta_rad[i], base.ref_theta_rad[i], 1e-9) << i;
}

TEST(DiagInput, NeverReadsTheSimulatedEffects) {
  const tracks::Track tr = simulate_track(short_run());
  tracks::TrackData d = tr.data();
  for (auto& [k, v] : d.meta.extra)
    if (k == "sim.effects") v = "this is not an effect list";
  const DiagInput a = build_diag_input(tr), b = build_diag_input(tracks::Track(std::move(d)));
  EXPECT_EQ(a.phi_l_rad, b.phi_l_rad);
  EXPECT_EQ(a.ref_x_m, b.ref_x_m);
  EXPECT_EQ(a.ref_sigma_m, b.ref_sigma_m);
  EXPECT_EQ(a.ref_sigma_rad, b.ref_sigma_rad);
}

TEST(DiagInput, ReferenceOutsideTheOdometrySpanIsDropped) {
  tracks::TrackData d;
  d.meta.name = "hand";
  d.meta.ticks_per_rev = 1000;
  d.meta.wheel_radius_left_m = d.meta.wheel_radius_right_m = 0.1;
  d.meta.wheel_base_m = 0.5;
  for (int i = 0; i < 10; ++i) d.t.push_back(0.1 * i);
  d.ticks_l = {tracks::kNoTick, 0, 10, 20, 30, 40, 50, 60, tracks::kNoTick, tracks::kNoTick};
  d.ticks_r = d.ticks_l;
  auto& gx = d.ensure(tracks::Col::gt_x);
  auto& gy = d.ensure(tracks::Col::gt_y);
  for (int i = 0; i < 10; ++i)
    gx[static_cast<std::size_t>(i)] = 0.01 * i, gy[static_cast<std::size_t>(i)] = 0.0;
  const DiagInput in = build_diag_input(tracks::Track(std::move(d)));
  ASSERT_EQ(in.odo_t_s.size(), 7u);
  EXPECT_DOUBLE_EQ(in.odo_t_s.front(), 0.1);
  EXPECT_EQ(in.phi_l_rad.front(), 0.0);
  EXPECT_DOUBLE_EQ(in.phi_l_rad.back(), 60 * 2 * std::numbers::pi / 1000);
  ASSERT_EQ(in.ref_t_s.size(), 7u);  // rows 1..7
  EXPECT_DOUBLE_EQ(in.ref_t_s.front(), 0.1);
  EXPECT_DOUBLE_EQ(in.ref_t_s.back(), 0.7);
}

TEST(DiagInput, ErrorsAreOneLineNamingTheTrack) {
  const tracks::Track tr = simulate_track(short_run());
  auto message = [](const tracks::Track& t) {
    try {
      build_diag_input(t);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  tracks::TrackData no_ref = tr.data();
  no_ref.col(tracks::Col::gt_x).clear();
  no_ref.col(tracks::Col::gt_y).clear();
  no_ref.col(tracks::Col::gt_theta).clear();
  const std::string m1 = message(tracks::Track(std::move(no_ref)));
  EXPECT_THAT(m1, HasSubstr("track 'sim_track'"));
  EXPECT_THAT(m1, HasSubstr("no reference"));
  EXPECT_EQ(m1.find('\n'), std::string::npos);

  tracks::TrackData no_radius = tr.data();
  no_radius.meta.wheel_radius_left_m.reset();
  EXPECT_THAT(message(tracks::Track(std::move(no_radius))), HasSubstr("robot.wheel_radius_left"));

  tracks::TrackData one_row;
  one_row.meta.name = "tiny";
  one_row.meta.ticks_per_rev = 100;
  one_row.meta.wheel_radius_left_m = one_row.meta.wheel_radius_right_m = 0.1;
  one_row.meta.wheel_base_m = 0.3;
  one_row.t = {0.0};
  one_row.ticks_l = one_row.ticks_r = {0};
  one_row.ensure(tracks::Col::gt_x)[0] = 0.0;
  one_row.ensure(tracks::Col::gt_y)[0] = 0.0;
  EXPECT_THAT(message(tracks::Track(std::move(one_row))), HasSubstr("no usable odometry"));

  tracks::TrackData few_fixes;
  few_fixes.meta.name = "few";
  few_fixes.t = {0.0, 1.0, 2.0};
  few_fixes.col(tracks::Col::v_cmd) = {0.1, 0.1, 0.1};
  few_fixes.col(tracks::Col::w_cmd) = {0.0, 0.0, 0.0};
  few_fixes.col(tracks::Col::aps_x) = {0.0, std::nan(""), 0.2};
  few_fixes.col(tracks::Col::aps_y) = {0.0, std::nan(""), 0.0};
  // Two fixes are accepted (only a track without any reference
  // sample is refused; diagnose() says when too few leave nothing to fit) ...
  tracks::TrackData outside = few_fixes;
  EXPECT_EQ(message(tracks::Track(std::move(few_fixes))), "no error");
  // ... but none within the odometry's time span is refused.
  outside.t = {0.0, 1.0, 2.0, 3.0};
  outside.col(tracks::Col::v_cmd) = {0.1, 0.1, std::nan(""), std::nan("")};
  outside.col(tracks::Col::w_cmd) = {0.0, 0.0, std::nan(""), std::nan("")};
  outside.col(tracks::Col::aps_x) = {std::nan(""), std::nan(""), 0.2, 0.3};
  outside.col(tracks::Col::aps_y) = {std::nan(""), std::nan(""), 0.0, 0.0};
  const std::string m2 = message(tracks::Track(std::move(outside)));
  EXPECT_THAT(m2, HasSubstr("no reference sample within the odometry's time span"));
  EXPECT_EQ(m2.find('\n'), std::string::npos);
}

// A real recording: UTIAS MRCLAM robot 1 (commanded body velocities, Vicon
// ground truth at irregular stamps, no sim.* metadata, no wheel base).
TEST(DiagInput, RealMrclamTrack) {
  const tracks::Track tr = tracks::import_mrclam(
      std::filesystem::path(ODOTUNE_SHARED_DIR) / "data" / "real" / "mrclam7", 1);
  const DiagInput in = build_diag_input(tr);
  EXPECT_EQ(in.odometry, OdometryKind::body_velocity);
  EXPECT_EQ(in.wheel_base_m, 0.0);
  EXPECT_GT(in.odo_t_s.size(), 10000u);
  EXPECT_EQ(in.reference, ReferenceKind::gt);
  EXPECT_TRUE(in.has_ref_heading());
  EXPECT_GT(in.ref_t_s.size(), 10000u);
  EXPECT_GE(in.ref_t_s.front(), in.odo_t_s.front());
  EXPECT_LE(in.ref_t_s.back(), in.odo_t_s.back());
  // Estimated (no metadata): Vicon is millimetre-class; the estimate is an upper bound.
  EXPECT_GE(in.ref_sigma_m, 1e-3);
  EXPECT_LT(in.ref_sigma_m, 0.02);
  EXPECT_GE(in.ref_sigma_rad, 1e-3);
  EXPECT_LT(in.ref_sigma_rad, 0.05);
  for (std::size_t i = 1; i < in.ref_theta_rad.size(); ++i)
    ASSERT_LT(std::abs(in.ref_theta_rad[i] - in.ref_theta_rad[i - 1]), 1.0) << "not unwrapped at " << i;
}

TEST(DiagInputCrop, KeepsTheRangeAndReZeroesTheWheels) {
  testing_support::SimTrackOptions o;
  o.duration_s = 40.0;
  o.seed = 91;
  const DiagInput in = build_diag_input(testing_support::simulate_track(o));
  const DiagInput c = crop(in, 10.0, 20.0);
  ASSERT_GE(c.odo_t_s.size(), 2u);
  EXPECT_GE(c.odo_t_s.front(), 10.0);
  EXPECT_LE(c.odo_t_s.back(), 20.0);
  EXPECT_GE(c.ref_t_s.front(), 10.0);
  EXPECT_LE(c.ref_t_s.back(), 20.0);
  EXPECT_EQ(c.ref_x_m.size(), c.ref_t_s.size());
  EXPECT_EQ(c.ref_theta_rad.size(), c.ref_t_s.size());
  EXPECT_EQ(c.gyro_z_radps.size(), c.gyro_t_s.size());
  EXPECT_EQ(c.phi_l_rad.size(), c.odo_t_s.size());
  EXPECT_EQ(c.phi_l_rad.front(), 0.0);
  EXPECT_EQ(c.phi_r_rad.front(), 0.0);
  // Increments are the original's.
  const auto k = static_cast<std::size_t>(std::find(in.odo_t_s.begin(), in.odo_t_s.end(), c.odo_t_s[5]) -
                                          in.odo_t_s.begin());
  ASSERT_LT(k, in.odo_t_s.size());
  EXPECT_NEAR(c.phi_l_rad[6] - c.phi_l_rad[5], in.phi_l_rad[k + 1] - in.phi_l_rad[k], 1e-12);
  EXPECT_THROW(crop(in, 20.0, 10.0), std::invalid_argument);
  EXPECT_THROW(crop(in, 1000.0, 2000.0), std::invalid_argument);
}

}  // namespace
}  // namespace odotune::diagnose

// navsat_transform_node as it runs: robot_localization's test_navsat_conversions
// (LLtoUTM, UTMtoLL) and test_navsat_transform (a datum's UTM zone kept across a
// zone boundary) reproduced, the manual datum (wait_for_datum with datum),
// use_odometry_yaw (the filter's own yaw as navsat's heading), and navsat's
// timer (frequency, delay).
#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

#include <GeographicLib/LocalCartesian.hpp>
#include <gtest/gtest.h>

#include <odotune/rlnode/geodesy.h>
#include <odotune/rlnode/params.h>
#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>

#include "support/rl_gps_bag.h"
#include "support/ros2_bag.h"
#include "support/temp_dir.h"

namespace rl = odotune::filters::rl;
using namespace odotune::rlnode;
using odotune::testing_support::BagMessageSpec;
using odotune::testing_support::TempDir;

namespace {

// test_navsat_conversions.cpp's NavsatConversionsTest, its tolerances: 1 cm,
// the zone, 0.01° of convergence; back to within 1e-5°.
void navsat_conversion(double lat, double lon, double northing, double easting, const std::string& zone,
                       double gamma_deg) {
  const UtmPoint p = utm_forward(lat, lon);
  EXPECT_NEAR(p.northing_m, northing, 1e-2);
  EXPECT_NEAR(p.easting_m, easting, 1e-2);
  EXPECT_EQ(utm_zone_designator(lat, lon), zone);
  EXPECT_NEAR(p.convergence_rad * 180.0 / std::numbers::pi, gamma_deg, 1e-2);
  UtmPoint q = p;
  q.northing_m = northing;
  q.easting_m = easting;
  double lat2 = 0, lon2 = 0;
  utm_reverse(q, &lat2, &lon2);
  EXPECT_NEAR(lat2, lat, 1e-5);
  EXPECT_NEAR(lon2, lon, 1e-5);
}

std::filesystem::path navsat_file(const TempDir& dir, const std::string& navsat) {
  const auto f = dir.path() / "p.yaml";
  std::ofstream(f)
      << "ekf:\n  ros__parameters:\n    frequency: 20.0\n    two_d_mode: true\n    odom0: /odom\n"
         "    odom0_config: [false, false, false, false, false, false, true, true, false, false, false, "
         "true, false, false, false]\n    odom1: /odometry/gps\n"
         "    odom1_config: [true, true, false, false, false, false, false, false, false, false, "
         "false, false, false, false, false]\nnavsat:\n  ros__parameters:\n    zero_altitude: true\n"
      << navsat;
  return f;
}

}  // namespace

TEST(RlNavsat, ConversionsAsRobotLocalizationsTest) {
  navsat_conversion(51.423964, 5.494271, 5699924.709, 673409.989, "31U", 1.950);
  navsat_conversion(-43.530955, 172.636645, 5178919.718, 632246.802, "59G", -1.127);
}

// test_navsat_transform's UtmTest: datum (1°, 4°); points at 10° N and 4.5°,
// 5.5° and 6.5° E (zone 32 begins at 6°) stay within 120 km and 240 km of each
// other in the odom frame, because every fix takes the datum's zone.
TEST(RlNavsat, DatumZoneIsKeptAcrossAZoneBoundary) {
  TempDir dir("rl-navsat-zone");
  std::vector<BagMessageSpec> msgs;
  const double lons[] = {4.5, 5.5, 6.5};
  for (int k = 0; k < 3; ++k) {
    const std::int64_t t = 1'000'000'000 + k * 500'000'000LL;
    msgs.push_back({0, static_cast<std::uint64_t>(t), odotune::testing_support::odometry(t, 0.0, 0.0)});
    msgs.push_back({1, static_cast<std::uint64_t>(t),
                    odotune::testing_support::navsatfix(t, 10.0, lons[k], 1.0)});
  }
  const auto bag = dir.path() / "zone.mcap";
  odotune::testing_support::write_ros2_mcap(
      bag, {{"/odom", "nav_msgs/msg/Odometry"}, {"/fix", "sensor_msgs/msg/NavSatFix"}}, msgs);
  const Recording rec = load_recording(
      bag, read_rl_params(navsat_file(dir, "    wait_for_datum: true\n    datum: [1.0, 4.0, 0.0]\n")));
  ASSERT_EQ(rec.fixes.size(), 3u);
  ASSERT_TRUE(rec.gps_transform.fixed);
  const Eigen::Vector3d a = fix_in_odom(rec.fixes[0], rec.gps_transform),
                        b = fix_in_odom(rec.fixes[1], rec.gps_transform),
                        c = fix_in_odom(rec.fixes[2], rec.gps_transform);
  EXPECT_NEAR(a.x(), b.x(), 120e3);
  EXPECT_NEAR(a.y(), b.y(), 120e3);
  EXPECT_NEAR(a.x(), c.x(), 2 * 120e3);
  EXPECT_NEAR(a.y(), c.y(), 2 * 120e3);
  // and the steps are even: 1° of longitude at 10° N is about 110 km each
  EXPECT_NEAR((b - a).norm(), (c - b).norm(), 1e3);
  // the datum itself is the odom frame's origin: 9° north of it, ~995 km
  EXPECT_NEAR(a.y(), utm_forward(10.0, 4.5, 31).northing_m - utm_forward(1.0, 4.0).northing_m, 5e3);
}

// wait_for_datum with a datum on a local plane: the datum is the odom origin,
// its heading the odom frame's x axis, so the fixes of a path turned by 0.3 rad
// in east/north fall on the odometry's own path.
TEST(RlNavsat, ManualDatumFixesTheTransform) {
  TempDir dir("rl-navsat-datum");
  const auto bag = odotune::testing_support::rl_gps_bag(dir.path(), 0.3);
  const Recording rec = load_recording(
      bag,
      read_rl_params(navsat_file(
          dir, "    use_local_cartesian: true\n    wait_for_datum: true\n    datum: [42.0, -71.0, 0.3]\n")));
  ASSERT_TRUE(rec.gps_transform.fixed);
  EXPECT_NEAR(rec.gps_transform.rotation_rad, -0.3, 1e-12);
  // fixes every 0.5 s of a 1 m/s drive along x: the 11th at (5, 0)
  const Eigen::Vector3d p0 = fix_in_odom(rec.fixes[0], rec.gps_transform);
  const Eigen::Vector3d p10 = fix_in_odom(rec.fixes[10], rec.gps_transform);
  EXPECT_NEAR(p0.head<2>().norm(), 0.0, 1e-6);
  // (the fixes are 10 m above the plane: its curvature moves them by µm)
  EXPECT_NEAR(p10.x(), 5.0, 1e-4);
  EXPECT_NEAR(p10.y(), 0.0, 1e-4);
}

// use_odometry_yaw: no IMU; the filter's yaw at the first fix (0, the drive
// starts straight along x) plus yaw_offset is navsat's heading, so yaw_offset
// 0.3 turns the fixes of a path turned by 0.3 rad back onto the odometry.
TEST(RlNavsat, OdometryYawIsTheHeading) {
  TempDir dir("rl-navsat-odomyaw");
  const auto bag = odotune::testing_support::rl_gps_bag(dir.path(), 0.3);
  const Recording rec = load_recording(
      bag, read_rl_params(navsat_file(
               dir, "    use_local_cartesian: true\n    use_odometry_yaw: true\n    yaw_offset: 0.3\n")));
  EXPECT_TRUE(rec.navsat_headings.empty());
  const ReplayOutput out = replay(rec, make_schedule(rec), settings_of(rec.params));
  EXPECT_NEAR(out.gps_transform.rotation_rad, -0.3, 1e-9);
  // the square closes where it began
  EXPECT_LT(out.final_state.head<2>().norm(), 0.2);
}

namespace {

// The GPS inputs of a schedule: (event, fix index, event time [ns]).
struct FixEvent {
  Event::Type type;
  int fix;
  std::int64_t time_ns;
};

std::vector<FixEvent> fix_events(const Recording& rec, const Schedule& s) {
  std::vector<FixEvent> out;
  for (const Event& e : s.events) {
    if ((e.type != Event::datum && e.type != Event::process) || rec.inputs[e.input].kind != InputKind::gps)
      continue;
    out.push_back({e.type, rec.inputs[e.input].fix, e.time_ns});
  }
  return out;
}

}  // namespace

// navsat_transform_node's timer: at 1 Hz after a 0.25 s delay it ticks at
// 1.25 s, 2.25 s, … after the bag's start (the fixes come at 2 Hz from 0 s;
// the filter publishes from 0 s). Its first tick takes the datum with the
// latest fix (1.0 s: fix 2); every later tick publishes the latest fix, the
// one of the last whole second (fix 4 at 2.25 s, …), so the half-second fixes
// never reach the filter (yaw_offset turns the fixes back onto the odometry), and the filter fuses each at the tick of 20 Hz that
// falls on navsat's, 0.25 s after the fix's stamp. A ROS 2 node sleeps whole
// seconds of its delay (none here): its ticks fall on the fixes.
TEST(RlNavsat, TimerPublishesTheLatestFixAtEachTick) {
  TempDir dir("rl-navsat-timer");
  const auto bag = odotune::testing_support::rl_gps_bag(dir.path(), 0.3);
  const std::string navsat =
      "    use_local_cartesian: true\n    use_odometry_yaw: true\n    yaw_offset: 0.3\n    frequency: 1.0\n"
      "    delay: 0.25\n";
  // the same keys in a ROS 1 file of their own (--navsat-params)
  const auto ros1 = dir.path() / "navsat1.yaml";
  std::ofstream(ros1)
      << "zero_altitude: true\nuse_local_cartesian: true\nuse_odometry_yaw: true\nyaw_offset: 0.3\n"
         "frequency: 1.0\ndelay: 0.25\n";
  const auto ekf_only = dir.path() / "ekf.yaml";
  {
    std::ifstream in(navsat_file(dir, navsat));
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(ekf_only) << text.substr(0, text.find("navsat:"));
  }
  const std::int64_t start = 1'000'000'000, s = 1'000'000'000, quarter = 250'000'000;
  for (const bool ros2 : {false, true}) {
    SCOPED_TRACE(ros2 ? "ROS 2" : "ROS 1");
    const RlParams p = ros2 ? read_rl_params(navsat_file(dir, navsat))
                            : read_rl_params(ekf_only, "", std::nullopt, ros1);
    ASSERT_EQ(p.navsat.ros2, ros2);
    const Recording rec = load_recording(bag, p);
    ASSERT_TRUE(rec.through_navsat());
    const std::int64_t lag = ros2 ? 0 : quarter;
    const std::vector<FixEvent> ev = fix_events(rec, make_schedule(rec));
    ASSERT_GT(ev.size(), 30u);
    EXPECT_EQ(ev[0].type, Event::datum);
    EXPECT_EQ(ev[0].fix, 2);
    EXPECT_EQ(ev[0].time_ns, start + s + lag);
    for (std::size_t k = 1; k < ev.size(); ++k) {
      SCOPED_TRACE(k);
      EXPECT_EQ(ev[k].type, Event::process);
      EXPECT_EQ(ev[k].fix, 2 * static_cast<int>(k) + 2);
      const GpsFix& f = rec.fixes[static_cast<std::size_t>(ev[k].fix)];
      EXPECT_EQ(f.stamp_ns, start + static_cast<std::int64_t>(k + 1) * s);
      EXPECT_EQ(ev[k].time_ns, f.stamp_ns + lag);
    }
    // the drive closes its square with the fixes it was given
    const ReplayOutput out = replay(rec, make_schedule(rec), settings_of(rec.params));
    EXPECT_NEAR(out.gps_transform.rotation_rad, -0.3, 1e-9);
    EXPECT_LT(out.final_state.head<2>().norm(), 0.3);
  }
}

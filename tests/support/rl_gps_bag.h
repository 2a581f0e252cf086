// Test support (header-only): a small ROS 2 bag for robot_localization's
// replay with GPS: odometry driving a 20 m square at 1 m/s, and GPS fixes of
// the same path turned by a heading in east/north; and a parameter file that
// fuses both (two_d_mode, navsat on a local tangent plane).
#pragma once

#include <cmath>
#include <filesystem>
#include <numbers>
#include <vector>

#include <GeographicLib/LocalCartesian.hpp>

#include "support/ros2_bag.h"

namespace odotune::testing_support {

// Odometry driving a 20 m square at 1 m/s in the odom frame, and GPS fixes
// (2 Hz, σ 1 cm) of the same path turned by `heading` [rad] in east/north.
inline std::filesystem::path rl_gps_bag(const std::filesystem::path& dir, double heading) {
  GeographicLib::LocalCartesian local(42.0, -71.0, 0.0);
  std::vector<BagMessageSpec> msgs;
  double x = 0.0, y = 0.0, yaw = 0.0;
  const double dt = 0.05;
  for (int k = 0; k <= 1600; ++k) {
    const std::int64_t t = 1'000'000'000 + k * 50'000'000LL;
    const double w = (k % 400 >= 380) ? (std::numbers::pi / 2) / (20 * dt) : 0.0;  // turn at each corner
    const double v = w == 0.0 ? 1.0 : 0.0;
    msgs.push_back({0, static_cast<std::uint64_t>(t), odometry(t, v, w)});
    if (k % 10 == 0) {
      const double e = std::cos(heading) * x - std::sin(heading) * y,
                   n = std::sin(heading) * x + std::cos(heading) * y;
      double lat = 0, lon = 0, h = 0;
      local.Reverse(e, n, 0.0, lat, lon, h);
      msgs.push_back({1, static_cast<std::uint64_t>(t), navsatfix(t, lat, lon, 1e-4)});
    }
    x += v * std::cos(yaw) * dt;
    y += v * std::sin(yaw) * dt;
    yaw += w * dt;
  }
  const auto path = dir / "gps.mcap";
  write_ros2_mcap(path, {{"/odom", "nav_msgs/msg/Odometry"}, {"/fix", "sensor_msgs/msg/NavSatFix"}}, msgs);
  return path;
}

inline const char* kRlGpsParams = R"(ekf:
  ros__parameters:
    frequency: 20.0
    two_d_mode: true
    odom0: /odom
    odom0_config: [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]
    odom1: /odometry/gps
    odom1_config: [true, true, false, false, false, false, false, false, false, false, false, false, false, false, false]
navsat:
  ros__parameters:
    zero_altitude: true
    use_local_cartesian: true
)";

}  // namespace odotune::testing_support

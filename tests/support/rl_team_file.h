// A team's robot_localization file for a wheeled robot with fixes, as the
// tests of robot_localization on tracks write it: the odometry's vx, vy, vyaw
// (odom0) and the fixes' x, y (odom1) at 20 Hz in two_d_mode; kRlGyroInput
// appended adds the gyro's yaw rate (imu0).
#pragma once

namespace odotune::testing_support {

inline constexpr const char* kRlTeamFile = R"(ekf_filter_node:
  ros__parameters:
    frequency: 20.0
    two_d_mode: true
    odom0: odom
    odom0_config: [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]
    odom1: odometry/fixes
    odom1_config: [true, true, false, false, false, false, false, false, false, false, false, false, false, false, false]
)";
inline constexpr const char* kRlGyroInput =
    "    imu0: imu/data\n"
    "    imu0_config: [false, false, false, false, false, false, false, false, false, false, false, true, false, "
    "false, false]\n";

}  // namespace odotune::testing_support

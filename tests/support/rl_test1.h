// Test support (header-only): robot_localization's test1.bag as its ROS 1
// bag1 test plays it.
#pragma once

#include <odotune/rlnode/frames.h>
#include <odotune/rlnode/recording.h>

namespace odotune::testing_support {

// The IMU mounting of robot_localization's ROS 1 bag1 test (static_transform_publisher
// 0 -0.3 0.52 -1.570796327 0 1.570796327 base_link imu_link: x y z yaw pitch roll),
// which is not in the bag.
inline rlnode::RecordingOptions test1_imu_mounting() {
  rlnode::RecordingOptions o;
  rlnode::Pose3 mount;
  mount.t = {0.0, -0.3, 0.52};
  mount.R = rlnode::rotation_rpy(1.570796327, 0.0, -1.570796327);
  o.frames["imu_link"] = mount;
  return o;
}

}  // namespace odotune::testing_support

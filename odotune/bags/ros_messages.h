// The ROS messages odotune imports, decoded from either wire encoding
// (odotune/bags/wire.h): the same struct whether the bag is ROS 1 or ROS 2.
//
// Field order and types are the message definitions (ROS 1 noetic / ROS 2
// humble common_interfaces, identical for these messages apart from the
// Header's seq, which only ROS 1 has and which is skipped). Stamps are integer
// nanoseconds since the epoch (a double would lose microseconds on today's
// Unix times). Each decode_* throws ByteReader::Short (a message cut off or
// declaring more elements than it holds) or std::runtime_error (bad CDR
// encapsulation); callers name the bag, topic and message.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/bags/wire.h>

namespace odotune::bags::ros {

struct Header {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
};
struct Vector3 {
  double x = 0, y = 0, z = 0;
};
struct Quaternion {
  double x = 0, y = 0, z = 0, w = 1;
};

// nav_msgs/Odometry: pose in header.frame_id, twist in child_frame_id.
struct Odometry {
  Header header;
  std::string child_frame_id;
  Vector3 position;
  Quaternion orientation;
  std::array<double, 36> pose_covariance{};
  Vector3 linear, angular;  // [m/s], [rad/s]
  std::array<double, 36> twist_covariance{};
};

// sensor_msgs/Imu (covariance[0] = −1 means "not provided", REP 145).
struct Imu {
  Header header;
  Quaternion orientation;
  std::array<double, 9> orientation_covariance{};
  Vector3 angular_velocity;  // [rad/s]
  std::array<double, 9> angular_velocity_covariance{};
  Vector3 linear_acceleration;  // [m/s²]
  std::array<double, 9> linear_acceleration_covariance{};
};

// sensor_msgs/NavSatFix. status −1: no fix. Covariance in ENU [m²],
// row-major; covariance_type 0 unknown, 1 approximated, 2 diagonal known,
// 3 known.
struct NavSatFix {
  Header header;
  std::int8_t status = 0;
  std::uint16_t service = 0;
  double latitude_deg = 0, longitude_deg = 0, altitude_m = 0;
  std::array<double, 9> position_covariance{};
  std::uint8_t covariance_type = 0;
};

// geometry_msgs/PoseStamped and PoseWithCovarianceStamped (the covariance
// only in the second).
struct PoseStamped {
  Header header;
  Vector3 position;
  Quaternion orientation;
  std::optional<std::array<double, 36>> covariance;
};

// sensor_msgs/JointState.
// geometry_msgs/TwistWithCovarianceStamped (robot_localization's twistN inputs).
struct TwistWithCovarianceStamped {
  Header header;
  Vector3 linear, angular;  // [m/s], [rad/s]
  std::array<double, 36> covariance{};
};

// geometry_msgs/Twist and TwistStamped (a command, e.g. cmd_vel; the header
// only in the second).
struct TwistStamped {
  Header header;
  Vector3 linear, angular;  // [m/s], [rad/s]
};

struct JointState {
  Header header;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;  // [rad], [rad/s], [N m]
};

// tf2_msgs/TFMessage (/tf, /tf_static).
struct TransformStamped {
  Header header;
  std::string child_frame_id;
  Vector3 translation;
  Quaternion rotation;
};
struct TFMessage {
  std::vector<TransformStamped> transforms;
};

// "nav_msgs/msg/Odometry" (ROS 2) → "nav_msgs/Odometry" (the ROS 1 name,
// used for both).
std::string normalise_type(std::string_view type);

Odometry decode_odometry(std::span<const std::uint8_t> data, WireEncoding encoding);
Imu decode_imu(std::span<const std::uint8_t> data, WireEncoding encoding);
NavSatFix decode_navsatfix(std::span<const std::uint8_t> data, WireEncoding encoding);
PoseStamped decode_pose_stamped(std::span<const std::uint8_t> data, WireEncoding encoding);
PoseStamped decode_pose_with_covariance_stamped(std::span<const std::uint8_t> data, WireEncoding encoding);
TwistWithCovarianceStamped decode_twist_with_covariance_stamped(std::span<const std::uint8_t> data,
                                                                WireEncoding encoding);
TwistStamped decode_twist(std::span<const std::uint8_t> data, WireEncoding encoding);
TwistStamped decode_twist_stamped(std::span<const std::uint8_t> data, WireEncoding encoding);
JointState decode_joint_state(std::span<const std::uint8_t> data, WireEncoding encoding);
TFMessage decode_tf_message(std::span<const std::uint8_t> data, WireEncoding encoding);

}  // namespace odotune::bags::ros

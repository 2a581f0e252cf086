// A robot's bag as robot_localization's ekf_node receives it: every message
// of a configured input prepared as the node's callbacks prepare it
// (ros_filter.cpp's odometryCallback, imuCallback, poseCallback,
// prepareTwist, preparePose, prepareAcceleration, read for behaviour), and
// the GPS fixes as navsat_transform_node turns them into odometry.
//
// What depends on the filter's state when a message arrives is left for the
// replay (odotune/rlnode/replay.h): the lever-arm terms of twists and accelerations
// measured away from base_link, gravity removed with the filter's attitude
// when the IMU gives no orientation, and the GPS datum (the filter's pose at
// the first fix). Everything else is done once here.
//
// Frames: a message's frame_id is base_link (or empty), the world frame for
// poses, or a frame whose pose in base_link is given (RecordingOptions::frames)
// or in the bag's /tf_static; any other frame is refused. The IMU's
// acceleration is handled as robot_localization's ROS 1 release does
// (gravity removed in the IMU's frame, then rotated into base_link).
//
// Errors: one line (std::invalid_argument), naming the bag, the parameter and
// what was expected: a configured topic missing from the bag or of another
// type, a frame without a transform.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <odotune/filters/rl_ekf.h>
#include <odotune/rlnode/frames.h>
#include <odotune/rlnode/params.h>

namespace odotune::rlnode {

// command: a cmd_vel message for use_control (its 6 velocities in the pool
// from `slot`, no covariance; `stamp_ns` the command's time).
enum class InputKind : std::uint8_t { twist, pose, imu_orientation, acceleration, gps, command };

// One measurement as the node enqueues it, in compact form: the fused members
// `idx[0..n)`, their values and covariance block in Recording::pool from
// `slot` (n values, then n·n row-major).
struct Input {
  std::int64_t stamp_ns = 0;    // header stamp: the time the filter gives it
  std::int64_t receive_ns = 0;  // the bag's receive time: when the callback ran
  InputKind kind = InputKind::twist;
  std::uint8_t sensor = 0;  // index into RlParams::sensors
  std::uint8_t n = 0;
  std::array<std::uint8_t, filters::rl::kStateSize> idx{};
  std::uint32_t slot = 0;
  double threshold = kNoRejection;  // Mahalanobis threshold [σ]
  // Origin of the sensor's frame in base_link [m]: the lever arm of the
  // twist's ω × r and the acceleration's α × r − (ω × r) × ω terms, and the GPS
  // antenna's offset that navsat_transform_node removes from each fix.
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();
  bool gravity_from_state = false;  // acceleration: remove g with the filter's attitude
  int fix = -1;                     // gps: index into Recording::fixes
};

// A NavSatFix in projected coordinates: UTM (navsat_transform_node's default)
// easting, northing [m] and altitude [m], with the grid's meridian convergence.
struct GpsFix {
  std::int64_t stamp_ns = 0, receive_ns = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();  // east, north, up [m²]
  double convergence_rad = 0.0;
};

// How navsat_transform_node's output is formed, once its datum is known.
struct GpsTransform {
  bool fixed = false;         // given (fitted or the datum parameter), not taken at the first fix
  double rotation_rad = 0.0;  // odom yaw of the grid's east axis
  Eigen::Vector3d grid_origin = Eigen::Vector3d::Zero();  // grid point mapped to odom_origin
  Eigen::Vector3d odom_origin = Eigen::Vector3d::Zero();
};

struct Recording {
  RlParams params;
  std::filesystem::path bag;
  std::vector<Input> inputs;  // in receive order (the node's callback order)
  std::vector<double> pool;
  std::vector<GpsFix> fixes;
  int gps_sensor = -1;    // the odomN that is navsat_transform_node's output, or −1
  std::string gps_topic;  // the NavSatFix topic read for it
  // The IMU's yaw (in base_link, as navsat_transform_node corrects it with its
  // mounting, declination and yaw_offset) from every orientation of navsat's
  // IMU, (receive time, yaw [rad]) in receive order: navsat's heading at its
  // datum is the last one before the timer's tick that takes it.
  std::vector<std::pair<std::int64_t, double>> navsat_headings;
  GpsTransform gps_transform;
  std::int64_t start_ns = 0, end_ns = 0;  // first and last receive time of an input
  // The receive time of the bag's first message of a configured topic: the
  // clock a user's seconds count from (RecordingOptions::from_s too).
  std::int64_t origin_ns = 0;
  std::vector<std::string> notes;  // what was read and converted, for the user

  // The fixes reach the filter through navsat_transform_node and its timer (a
  // bag's NavSatFix topic); false: they are in the world frame already (a track).
  bool through_navsat() const { return !gps_topic.empty(); }
};

// navsat's IMU heading at time `at` (receive time, yaw): its last orientation
// received by then; null when none was.
const std::pair<std::int64_t, double>* navsat_heading_at(const Recording& rec, std::int64_t at);

struct RecordingOptions {
  // frame_id → its pose in base_link; takes precedence over /tf_static.
  std::map<std::string, Pose3> frames;
  std::string gps_topic;  // NavSatFix topic for navsat's output; empty: the bag's one
  // Topic remappings (`rosrun … FROM:=TO`): a subscription to FROM (an input's
  // topic, cmd_vel) reads TO. Names as the node resolves them: "cmd_vel" is "/cmd_vel".
  std::map<std::string, std::string> remap;
  // > 0: the messages received in the first from_s seconds of the bag are left
  // out, as if it had been recorded from there (the node and navsat start then).
  double from_s = 0.0;
};

Recording load_recording(const std::filesystem::path& bag, const RlParams& params,
                         const RecordingOptions& options = {});

}  // namespace odotune::rlnode

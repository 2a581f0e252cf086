// robot_localization's parameters as its ekf_node, ukf_node and navsat_transform_node
// read them (robot_localization's src/ros_filter.cpp loadParams() and
// navsat_transform.cpp, read for behaviour): the user's own parameter file,
// ROS 1 rosparam YAML (`NODE: {key: value}` or the keys at the top level) or
// ROS 2 (`NODE: {ros__parameters: {…}}`), with the node's defaults where a key
// is missing. A parameter that would change the estimate and that the replay
// does not reproduce is refused by name; a key the node does not read is left
// out and noted (RlParams::notes).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <odotune/filters/rl_filter.h>

namespace odotune::rlnode {

using Matrix15 = Eigen::Matrix<double, 15, 15>;
using Vector15 = Eigen::Matrix<double, 15, 1>;
using UpdateMask = std::array<bool, 15>;  // x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az

// robot_localization's FilterBase defaults (its params/ekf.yaml says the same).
Matrix15 default_process_noise();
// 1e-9 on the diagonal (FilterBase::reset).
Matrix15 default_initial_estimate_covariance();

enum class SensorKind { odom, imu, pose, twist };
std::string_view to_string(SensorKind k);  // "odom", "imu", "pose", "twist"

constexpr double kNoRejection = std::numeric_limits<double>::max();

// One input: odomN, imuN, poseN or twistN and its keys.
struct SensorParams {
  SensorKind kind = SensorKind::odom;
  int index = 0;        // N of odomN
  std::string name;     // "odom0"
  std::string topic;    // the value of odomN
  UpdateMask config{};  // odomN_config (15 booleans; all false when missing)
  bool differential = false;
  bool relative = false;  // false when differential is also true (the node's rule)
  // odomN_pose_use_child_frame: the odometry's pose is its child frame's,
  // turned into base_link's through that frame's pose in base_link.
  bool pose_use_child_frame = false;
  // Mahalanobis thresholds [σ]: odomN_pose_/_twist_rejection_threshold,
  // poseN_/twistN_rejection_threshold (in pose/twist), imuN_pose_/_twist_/
  // _linear_acceleration_rejection_threshold. kNoRejection when not given.
  double pose_rejection_threshold = kNoRejection;
  double twist_rejection_threshold = kNoRejection;
  double accel_rejection_threshold = kNoRejection;
  bool remove_gravitational_acceleration = false;  // imuN_remove_gravitational_acceleration
  int yaml_line = 0;                               // line of the odomN key in the file (1-based), for messages
};

// navsat_transform_node's keys (its section of the file, when present).
struct NavsatParams {
  bool present = false;
  std::string node_name;       // the section's name in the file
  double frequency_hz = 10.0;  // its timer's rate
  double delay_s = 0.0;        // its timer starts this long after the node [s]
  bool ros2 = false;           // the form of the file it came from: ROS 2 sleeps whole seconds of delay_s
  double magnetic_declination_radians = 0.0;
  double yaw_offset = 0.0;  // [rad]
  bool zero_altitude = false;
  bool use_local_cartesian = false;  // false: the UTM grid (the node's default)
  bool use_odometry_yaw = false;
  bool wait_for_datum = false;
  std::optional<std::array<double, 3>> datum;  // latitude [deg], longitude [deg], heading [rad]
};

// use_control as the node reads it (ros_filter.cpp loadParams): the commands
// on `cmd_vel` turned into accelerations (odotune/filters/rl_control.h).
struct ControlParams {
  bool enabled = false;  // use_control, and a member left to control after the node's checks
  // ROS 1's stamped_control: TwistStamped, at its header's stamp; otherwise
  // Twist, at the time the node receives it (ROS 2 always so).
  bool stamped = false;
  std::string topic = "cmd_vel";
  filters::rl::RlControlParams filter;
};

// What the replay makes of a key of the file: reproduced (as the node uses
// it), no effect on a replay (what the node publishes, queues, logs), not read
// by robot_localization either (left out).
enum class KeyUse { reproduced, no_effect, not_read };
std::string_view to_string(KeyUse u);  // "reproduced", "no effect", "not read"

struct KeyReport {
  std::string section;  // the filter's or navsat_transform_node's section ("ekf_node" for a flat file)
  std::string key;
  int line = 0;  // 1-based
  KeyUse use = KeyUse::reproduced;
};

struct RlParams {
  std::filesystem::path file;
  bool ros2 = true;       // the file's form: ROS 2 (ros__parameters) or ROS 1
  std::string node_name;  // the filter's section name ("" when keys are at the top level)
  // ekf_node or ukf_node: a section whose name has "ukf" in it, or one with
  // ukf_node's alpha, kappa or beta, is the UKF's; read_rl_params' `filter`
  // decides for a file that does not say.
  filters::rl::RlFilterType filter = filters::rl::RlFilterType::ekf;
  filters::rl::UkfConstants ukf;  // alpha, kappa, beta (the UKF's only)
  double frequency_hz = 30.0;
  double sensor_timeout_s = 1.0 / 30.0;  // default 1/frequency
  bool two_d_mode = false;
  bool predict_to_current_time = false;
  bool dynamic_process_noise_covariance = false;
  double gravitational_acceleration = 9.80665;  // [m/s²]
  std::string map_frame = "map", odom_frame = "odom", base_link_frame = "base_link", world_frame = "odom";
  Matrix15 process_noise_covariance = default_process_noise();
  Matrix15 initial_estimate_covariance = default_initial_estimate_covariance();
  std::optional<Vector15> initial_state;
  std::vector<SensorParams> sensors;  // odom0, odom1, …, then pose*, twist*, imu* (the node's order)
  ControlParams control;
  // smooth_lagged_data: a message older than the filter's last measurement
  // re-filters from the state saved before it, over history_length.
  bool smooth_lagged_data = false;
  std::int64_t history_length_ns = 0;
  NavsatParams navsat;
  // "FILE:LINE: …" for each key left out because robot_localization does not
  // read it either (not one of its parameters; an input past the first gap of
  // its numbering) and each duplicate key with the same value, for the user.
  std::vector<std::string> notes;
  // Every key of the filter's and navsat's sections, in file order (each
  // duplicate once), with what the replay makes of it.
  std::vector<KeyReport> keys;
};

// Reads the file. `node_name` picks the EKF's section when the file has
// several (empty: the one section that has odomN/imuN/poseN/twistN keys, or
// the top level). Throws std::invalid_argument with one line
// "FILE:LINE: what is wrong, what was expected" for: a file that is not
// YAML, no EKF section or several without `node_name`, a key given twice
// with different values, a value of the wrong type or size (a covariance must have 15 or
// 225 entries, a _config 15 booleans), a negative frequency or timeout, and a
// supported key's value the replay does not reproduce, named:
// disabled_at_startup: true,
// smooth_lagged_data with use_control,
// navsat wait_for_datum: true without a datum. `filter` (the command line's --filter) picks
// the filter for a file that does not say which; ekf for a file with
// ukf_node's alpha, kappa or beta is refused, naming the key.
// `navsat_file` (--navsat-params): navsat_transform_node's parameters from a
// file of their own (Nav2's and Heron's teams keep them apart); refused when
// `file` has a navsat section too.
RlParams read_rl_params(const std::filesystem::path& file, const std::string& node_name = "",
                        std::optional<filters::rl::RlFilterType> filter = std::nullopt,
                        const std::filesystem::path& navsat_file = {});

// A navsat_transform_node file alone (for `eval --keys`): RlParams with only
// `navsat`, `keys` and `notes` filled. Throws as read_rl_params, and for a file
// that has a filter section.
RlParams read_navsat_params(const std::filesystem::path& file);

// What a tune changes in the file.
struct RlParamsUpdate {
  std::optional<Matrix15> process_noise_covariance;
  std::optional<Matrix15> initial_estimate_covariance;
  // per sensor name ("odom0"): new thresholds, kNoRejection leaves the key out
  std::vector<std::pair<std::string, std::array<double, 3>>> rejection_thresholds;  // pose, twist, accel
  std::optional<double> navsat_yaw_offset;
  // ukf_node's constants, written as alpha, kappa and beta: the file then says
  // that it is the UKF's, whatever its section's name.
  std::optional<filters::rl::UkfConstants> ukf;
};

// The user's file with `update`'s values substituted (other keys, their order
// and the file's form kept), as text in the form asked: ROS 2 when `ros2`,
// else ROS 1 (`NODE: {key: value}`), with `header_comment` (lines without
// '#', each written as a comment) at the top. Covariances are written as 15
// rows of 15 entries.
std::string write_rl_params(const std::filesystem::path& original, const RlParams& params,
                            const RlParamsUpdate& update, bool ros2, const std::string& header_comment);

}  // namespace odotune::rlnode

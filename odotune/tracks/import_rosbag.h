// A robot's own recording, a ROS bag (ROS 1 .bag, MCAP, rosbag2 SQLite or a
// rosbag2 folder; odotune/bags/bag.h), converted to a track (odotune-track/1,
// ../shared/specs/track-format.md).
//
// What becomes which column:
//   odometry  nav_msgs/Odometry: twist.linear.x → v_cmd, twist.angular.z →
//             w_cmd (body velocities "as reported by the base");
//             sensor_msgs/JointState: the two wheel joints' velocities (or,
//             without velocities, their positions differenced) → omega_l,
//             omega_r [rad/s], which needs the wheel radius and base.
//   gyro      sensor_msgs/Imu angular_velocity rotated into the base frame
//             (the IMU's mounting rotation: given roll, pitch, yaw, or from
//             /tf_static, else none with a note) → its z component, gyro_z.
//   fixes     sensor_msgs/NavSatFix → aps_x (east), aps_y (north) [m] in a
//             local tangent frame at the first fix (GeographicLib's
//             LocalCartesian on WGS84); its covariance's east and north
//             variances → aps_var_x, aps_var_y when the covariance type is
//             not "unknown"; fixes with status −1 (no fix) are dropped.
//             geometry_msgs/PoseWithCovarianceStamped or PoseStamped →
//             aps_x, aps_y (position) and, with a covariance, its variances.
//   ground    nav_msgs/Odometry, PoseStamped or PoseWithCovarianceStamped →
//   truth     gt_x, gt_y, gt_theta (yaw of the orientation); only from a
//             topic named with gt_topic (a bag's own odometry pose is not
//             ground truth).
// Topics left empty are found from the message types: the one topic of the
// type, or, for odometry, the one Odometry topic whose name does not look
// like a filter's output; when several fit, the import stops and lists them.
//
// Time: each message at its header stamp (or, with `receive_time_stamps`,
// the time the bag recorded it: rosbag's receive time, which is simulated
// time when the robot ran in simulation); t = 0 at the earliest stamp used,
// with `source.t0_ns` the absolute start. Messages of one topic whose stamps
// go backwards are sorted and counted; a stamp repeated on one topic keeps
// its first message and counts the rest; a topic whose header stamps are all
// zero is refused (use receive times). Messages of different topics at the
// same stamp share a row.
//
// The metadata cites the bag, its format, every topic and every conversion
// (source, source.*), and robot.* from the options when given.
//
// Errors: bags::BagError for a bag that cannot be read, TrackError (the bag
// as the file, line 0) for a missing or ambiguous topic, a wrong type, bad
// options or nothing to import. Nothing is written here (odotune/jobs/import_job.h
// writes the track atomically).
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <odotune/tracks/track.h>

namespace odotune::tracks {

struct RosbagImportOptions {
  std::string odom_topic;                            // empty: found from the types
  std::string imu_topic;                             // empty: found; "none": no gyro
  std::string fix_topic;                             // empty: found; "none": no fixes
  std::string gt_topic;                              // empty: no ground truth
  std::optional<std::array<double, 3>> imu_rpy_rad;  // IMU mounting roll, pitch, yaw relative to the base frame
  bool receive_time_stamps = false;                  // true: bag receive times instead of header stamps
  // JointState odometry: the wheel joints and the geometry.
  std::string left_joint, right_joint;
  std::optional<double> wheel_radius_m, wheel_base_m;
};

Track import_rosbag(const std::filesystem::path& bag, const RosbagImportOptions& options);

// The bag's topics as lines "  NAME  TYPE  COUNT", for listings.
std::vector<std::string> describe_bag_topics(const std::filesystem::path& bag);

}  // namespace odotune::tracks

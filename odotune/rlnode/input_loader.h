// The node's callbacks, one message at a time (internal to rlnode/: used by
// recording.cpp). See recording.h for what is prepared here and what is left
// to the replay.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include <GeographicLib/LocalCartesian.hpp>

#include <odotune/bags/ros_messages.h>
#include <odotune/filters/rl_ekf.h>
#include <odotune/rlnode/recording.h>

namespace odotune::rlnode::detail {

namespace rl = filters::rl;
namespace ros = bags::ros;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Cov36 = std::array<double, 36>;

// A measurement before it is stored compactly.
struct Prepared {
  rl::State z = rl::State::Zero();
  rl::Cov R = rl::Cov::Zero();
  rl::Mask mask{};
};

inline std::string with_slash(const std::string& topic) {
  return topic.empty() || topic[0] == '/' ? topic : "/" + topic;
}

// RosFilter::forceTwoD: z, roll, pitch and their rates and a_z measured as 0.
inline void force_two_d(Prepared& m) {
  for (int i : {rl::kZ, rl::kRoll, rl::kPitch, rl::kVz, rl::kVroll, rl::kVpitch, rl::kAz}) {
    m.z[i] = 0.0;
    m.R(i, i) = 1e-6;
    m.mask[i] = true;
  }
}

// The node's rotation of an update mask: the rows of R·diag(mask) that are
// not (numerically) zero.
inline void rotate_mask(rl::Mask& mask, int offset, const Eigen::Matrix3d& R) {
  const Eigen::Vector3d d(mask[offset], mask[offset + 1], mask[offset + 2]);
  const Eigen::Matrix3d M = R * d.asDiagonal();
  for (int i = 0; i < 3; ++i) mask[offset + i] = M.row(i).norm() >= 1e-6;
}

inline Mat6 block_rotation(const Eigen::Matrix3d& R) {
  Mat6 r = Mat6::Zero();
  r.topLeftCorner<3, 3>() = R;
  r.bottomRightCorner<3, 3>() = R;
  return r;
}

inline Mat6 to_mat6(const Cov36& c) {
  return Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(c.data());
}

inline Eigen::Matrix3d yaw_rotation(double yaw) { return rotation_rpy(0.0, 0.0, yaw); }

// An IMU's reported orientation as the node and navsat take it for base_link
// (preparePose's IMU branch): the mounting's roll, pitch and yaw subtracted,
// the result turned by the mounting's yaw.
inline Eigen::Matrix3d imu_orientation_in_base(const Eigen::Matrix3d& reported, const Pose3& mount) {
  const Rpy off = rpy_of(mount.R), a = rpy_of(reported);
  const Eigen::Vector3d rpy = yaw_rotation(off.yaw) *
                              Eigen::Vector3d(filters::rl::normalize_angle(a.roll - off.roll),
                                              filters::rl::normalize_angle(a.pitch - off.pitch),
                                              filters::rl::normalize_angle(a.yaw - off.yaw));
  return rotation_rpy(rpy.x(), rpy.y(), rpy.z());
}

struct PoseInput {
  std::int64_t stamp_ns = 0, receive_ns = 0;
  std::string frame;
  Pose3 pose;
  Mat6 cov = Mat6::Zero();
  bool imu = false;
  // The frame whose pose this is (odomN_pose_use_child_frame: the child
  // frame); empty: base_link.
  std::string source;
};

struct TwistInput {
  std::int64_t stamp_ns = 0, receive_ns = 0;
  std::string frame;
  Eigen::Vector3d lin = Eigen::Vector3d::Zero(), ang = Eigen::Vector3d::Zero();
  Mat6 cov = Mat6::Zero();
};

class Loader {
 public:
  Loader(const RlParams& params, const RecordingOptions& options, Recording& rec)
      : p_(params), o_(options), rec_(rec) {}

  void set_static_frames(std::map<std::string, Pose3> frames) { tf_ = std::move(frames); }

  void on_odometry(const ros::Odometry& m, int s, std::int64_t receive_ns);
  void on_pose(const ros::PoseStamped& m, int s, std::int64_t receive_ns);
  void on_twist(const ros::TwistWithCovarianceStamped& m, int s, std::int64_t receive_ns);
  void on_imu(const ros::Imu& m, int s, std::int64_t receive_ns);
  void on_fix(const ros::NavSatFix& m, std::int64_t receive_ns);
  // A fix already projected (in the odom frame under an identity transform),
  // its antenna at base_link.
  void on_local_fix(const GpsFix& fix);
  // navsat's manual datum (latitude, longitude [deg], heading [rad]): sets the
  // grid every fix is projected on; returns the transform it fixes.
  GpsTransform set_datum(const std::array<double, 3>& datum);
  void note_imu_orientation(const ros::Imu& m, std::int64_t receive_ns);
  void on_command(const ros::TwistStamped& m, std::int64_t receive_ns);
  void finish();

 private:
  const SensorParams& sensor(int s) const { return p_.sensors[s]; }
  // The frame's pose in base_link: base_link itself, --tf, then /tf_static;
  // null when none gives it.
  const Pose3* find_frame(const std::string& frame) const;
  // The same, or a one-line refusal naming sensor `s`.
  Pose3 frame_in_base(const std::string& frame, int s) const;
  bool in_order(const std::string& callback, std::int64_t stamp_ns);
  // navsat's output for a projected fix, from the antenna in frame `frame_id`.
  void add_fix(const GpsFix& f, const std::string& frame_id);
  void store(const Prepared& m, InputKind kind, int s, std::int64_t stamp_ns, std::int64_t receive_ns,
             double threshold, const Eigen::Vector3d& lever = Eigen::Vector3d::Zero(),
             bool gravity_from_state = false, int fix = -1);
  void prepare_pose(const PoseInput& in, int s, rl::Mask mask, const std::string& callback);
  void prepare_twist(const TwistInput& in, int s, rl::Mask mask, double threshold, InputKind kind);
  void prepare_differential(const PoseInput& in, const Pose3& pose, const Mat6& cov_rotated, const Mat6& cov,
                            const Mat6& rot6, int s, const rl::Mask& mask, const std::string& callback);
  void prepare_acceleration(const ros::Imu& m, int s, std::int64_t receive_ns);

  const RlParams& p_;
  const RecordingOptions& o_;
  Recording& rec_;
  std::map<std::string, Pose3> tf_;
  std::map<std::string, std::int64_t> last_stamp_;
  struct Previous {
    Pose3 pose;
    Mat6 cov;
    std::int64_t stamp_ns = 0;
  };
  std::map<std::string, Previous> previous_;
  std::map<std::string, Pose3> initial_;
  long out_of_order_ = 0, no_fix_ = 0, repeated_differential_ = 0, commands_ = 0, foreign_commands_ = 0;
  std::unique_ptr<GeographicLib::LocalCartesian> local_;
  int utm_zone_ = -1;
};

}  // namespace odotune::rlnode::detail

// Rigid transforms and Euler angles as robot_localization uses them (tf2's
// conventions): roll, pitch, yaw are extrinsic X, Y, Z rotations, R =
// Rz(yaw)·Ry(pitch)·Rx(roll); a frame's pose in its parent maps child
// coordinates to parent ones, p_parent = R·p_child + t.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace odotune::rlnode {

struct Pose3 {
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  bool is_identity() const { return t.isZero(0.0) && R.isIdentity(0.0); }
};

struct Rpy {
  double roll = 0, pitch = 0, yaw = 0;  // [rad]
};

// R = Rz(yaw)·Ry(pitch)·Rx(roll) (tf2's Matrix3x3::setRPY).
inline Eigen::Matrix3d rotation_rpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// The angles of R as tf2's Matrix3x3::getRPY gives them (first solution:
// pitch in [−π/2, π/2]; at gimbal lock yaw = 0 and roll takes the rest).
Rpy rpy_of(const Eigen::Matrix3d& R);

// A quaternion (x, y, z, w) as a rotation matrix, normalised (as tf2's
// matrix from a quaternion is); the identity when all four are zero.
Eigen::Matrix3d rotation_of_quaternion(double x, double y, double z, double w);

}  // namespace odotune::rlnode

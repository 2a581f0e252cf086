#include <odotune/rlnode/frames.h>

#include <cmath>
#include <numbers>

namespace odotune::rlnode {

Rpy rpy_of(const Eigen::Matrix3d& R) {
  Rpy a;
  if (std::abs(R(2, 0)) >= 1.0) {
    a.yaw = 0.0;
    const double delta = std::atan2(R(2, 1), R(2, 2));
    a.pitch = R(2, 0) < 0.0 ? std::numbers::pi / 2.0 : -std::numbers::pi / 2.0;
    a.roll = delta;
    return a;
  }
  a.pitch = -std::asin(R(2, 0));
  const double cp = std::cos(a.pitch);
  a.roll = std::atan2(R(2, 1) / cp, R(2, 2) / cp);
  a.yaw = std::atan2(R(1, 0) / cp, R(0, 0) / cp);
  return a;
}

Eigen::Matrix3d rotation_of_quaternion(double x, double y, double z, double w) {
  if (x == 0.0 && y == 0.0 && z == 0.0 && w == 0.0) return Eigen::Matrix3d::Identity();
  // tf2 builds the matrix with 2/|q|², which is the normalised quaternion's.
  return Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
}

}  // namespace odotune::rlnode

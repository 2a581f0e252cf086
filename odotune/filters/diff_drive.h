// Differential-drive motion model on the pose (x, y, θ) driven by wheel
// travel, with its Jacobians.
//
// Model (midpoint integration of the track format's kinematics,
// ../shared/specs/track-format.md): with l, r the distances travelled by the
// left and right wheel over one step [m] and D the wheel base [m],
//   d  = (l + r) / 2,   Δθ = (r − l) / D,   θm = θ + Δθ / 2,
//   x' = x + d·cos θm,  y' = y + d·sin θm,  θ' = θ + Δθ.
// F = ∂(x',y',θ')/∂(x,y,θ) and V = ∂(x',y',θ')/∂(l,r) are the Jacobians the
// EKF propagates covariance with (Kovacs et al., eq. 5: R = V·diag(σl²,σr²)·Vᵀ).
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace odotune::filters {

// Named state indices (no magic numbers in Jacobians).
enum StateIndex : int { kX = 0, kY = 1, kTheta = 2, kStateDim = 3 };
// Named control indices.
enum ControlIndex : int { kLeft = 0, kRight = 1, kControlDim = 2 };

using Pose = Eigen::Matrix<double, kStateDim, 1>;
using StateCov = Eigen::Matrix<double, kStateDim, kStateDim>;
using ControlJacobian = Eigen::Matrix<double, kStateDim, kControlDim>;

// One step of wheel travel.
struct WheelTravel {
  double left_m = 0.0;
  double right_m = 0.0;
};

struct MotionStep {
  Pose next;          // pose after the step
  StateCov F;         // ∂next/∂pose
  ControlJacobian V;  // ∂next/∂(l, r)
};

// Applies the motion model to `pose`; `wheel_base_m` > 0. The pose part is
// odotune/core/planar_motion.h's midpoint_advance (same operations in the same order).
inline MotionStep diff_drive_step(const Pose& pose, WheelTravel u, double wheel_base_m) {
  const double d = 0.5 * (u.left_m + u.right_m);
  const double dtheta = (u.right_m - u.left_m) / wheel_base_m;
  const double theta_m = pose(kTheta) + 0.5 * dtheta;
  const double c = std::cos(theta_m);
  const double s = std::sin(theta_m);

  MotionStep out;
  out.next(kX) = pose(kX) + d * c;
  out.next(kY) = pose(kY) + d * s;
  out.next(kTheta) = pose(kTheta) + dtheta;

  out.F.setIdentity();
  out.F(kX, kTheta) = -d * s;
  out.F(kY, kTheta) = d * c;

  // ∂θm/∂l = −1/(2D), ∂θm/∂r = +1/(2D), ∂d/∂l = ∂d/∂r = 1/2.
  const double k = d / (2.0 * wheel_base_m);
  out.V(kX, kLeft) = 0.5 * c + k * s;
  out.V(kX, kRight) = 0.5 * c - k * s;
  out.V(kY, kLeft) = 0.5 * s - k * c;
  out.V(kY, kRight) = 0.5 * s + k * c;
  out.V(kTheta, kLeft) = -1.0 / wheel_base_m;
  out.V(kTheta, kRight) = 1.0 / wheel_base_m;
  return out;
}

}  // namespace odotune::filters

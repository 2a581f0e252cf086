#include <odotune/filters/ekf.h>

#include <cmath>
#include <stdexcept>

#include <odotune/core/why.h>

namespace odotune::filters {

std::string_view to_string(Divergence d) {
  switch (d) {
    case Divergence::none: return "none";
    case Divergence::non_finite: return "non_finite";
    case Divergence::covariance_not_pd: return "covariance_not_pd";
  }
  return "?";
}

bool EkfParams::IsValid(std::string* why) const {
  if (!noise.IsValid(why)) return false;
  if (!std::isfinite(wheel_base_m) || wheel_base_m <= 0.0) {
    return core::invalid(why, "wheel_base_m = " + std::to_string(wheel_base_m) + ": expected > 0");
  }
  if (!initial_pose.allFinite()) {
    return core::invalid(why, "initial_pose: expected finite values");
  }
  if (!is_positive_definite(initial_cov)) {
    return core::invalid(why, "initial_cov: expected a positive definite matrix");
  }
  return true;
}

bool is_positive_definite(const StateCov& P) {
  if (!P.allFinite()) return false;
  const double m1 = P(0, 0);
  const double m2 = P(0, 0) * P(1, 1) - P(0, 1) * P(1, 0);
  return m1 > 0.0 && m2 > 0.0 && P.determinant() > 0.0;
}

Ekf::Ekf(const EkfParams& params)
    : noise_(params.noise),
      wheel_base_m_(params.wheel_base_m),
      x_(params.initial_pose),
      P_(params.initial_cov) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("EkfParams: " + why);
}

StateCov Ekf::predict(WheelTravel u, double abs_yaw_rate_rad_s) {
  const MotionStep step = diff_drive_step(x_, u, wheel_base_m_);
  StateCov R = process_noise(noise_, u, abs_yaw_rate_rad_s, step.V);  // not const: returned by move
  x_ = step.next;
  P_ = step.F * P_ * step.F.transpose() + R;
  return R;
}

void Ekf::update(const Position& z) { update(z, noise_.q_x_m2, noise_.q_y_m2); }

void Ekf::update(const Position& z, double q_x_m2, double q_y_m2) {
  // H = [I₂ 0]: the fix observes x and y directly.
  const Eigen::Matrix2d S = P_.topLeftCorner<2, 2>() +
                            Eigen::Vector2d(q_x_m2, q_y_m2).asDiagonal().toDenseMatrix();
  const Eigen::Matrix<double, kStateDim, 2> PHt = P_.leftCols<2>();
  const Eigen::Matrix<double, kStateDim, 2> K = PHt * S.inverse();
  const Eigen::Vector2d innovation = z - x_.head<2>();
  x_ += K * innovation;
  P_ -= K * PHt.transpose();
  P_ = 0.5 * (P_ + P_.transpose()).eval();
}

Divergence Ekf::check() {
  if (div_ != Divergence::none) return div_;
  if (!x_.allFinite() || !P_.allFinite())
    div_ = Divergence::non_finite;
  else if (!is_positive_definite(P_))
    div_ = Divergence::covariance_not_pd;
  return div_;
}

}  // namespace odotune::filters

// The three EKF noise models of Kovacs et al., "Evaluation of Optimal
// Covariance Models for EKF-based Wheeled Mobile Robot Localization"
// (../shared/papers/001_*.txt, §2.3), in SI units.
//
//   rq:    process noise R = diag(r_x, r_y, r_θ) added at every prediction
//          step, measurement noise Q = diag(q_x, q_y)            (eq. 1, 2)
//   alpha: wheel-travel variances σl² = (α1·l)² + (α2·(l−r))²,
//          σr² = (α1·r)² + (α2·(l−r))², R = V·diag(σl², σr²)·Vᵀ    (eq. 3–5)
//   gyro:  as alpha with α1 = a1 + b1·|ω_z|, α2 = a2 + b2·|ω_z|     (eq. 6, 7)
//
// The alpha model is the gyro model with b1 = b2 = 0, and both are held in
// the same fields. (The paper calls process noise R and measurement noise Q,
// the reverse of much of the literature; we keep the paper's letters.)
#pragma once

#include <array>
#include <string>
#include <string_view>

#include <odotune/filters/diff_drive.h>

namespace odotune::filters {

enum class NoiseModel { rq, alpha, gyro };
inline constexpr std::array<NoiseModel, 3> kAllNoiseModels = {NoiseModel::rq, NoiseModel::alpha,
                                                              NoiseModel::gyro};

std::string_view to_string(NoiseModel m);
// Parses "rq", "alpha" or "gyro"; returns false on anything else.
bool parse_noise_model(std::string_view text, NoiseModel* out);

struct NoiseParams {
  NoiseModel model = NoiseModel::alpha;
  // rq only: process noise per prediction step [m², m², rad²].
  double r_x_m2 = 0.0, r_y_m2 = 0.0, r_theta_rad2 = 0.0;
  // Measurement noise of a position fix [m²] (all models).
  double q_x_m2 = 0.06 * 0.06, q_y_m2 = 0.06 * 0.06;
  // alpha and gyro: α1 = a1 + b1·|ω_z|, α2 = a2 + b2·|ω_z| [-, s/rad].
  double a1 = 0.0, a2 = 0.0, b1 = 0.0, b2 = 0.0;

  // False (with the bad value named in *why) when a value is negative,
  // non-finite, a measurement variance is not positive, or b1/b2 are non-zero
  // for the alpha model.
  bool IsValid(std::string* why) const;
};

// σl², σr² of eq. 3–4 with α from eq. 6–7 for one step; |ω_z| in rad/s.
inline void wheel_variances(const NoiseParams& p, WheelTravel u, double abs_yaw_rate_rad_s, double* var_l_m2,
                            double* var_r_m2) {
  const double alpha1 = p.a1 + p.b1 * abs_yaw_rate_rad_s;
  const double alpha2 = p.a2 + p.b2 * abs_yaw_rate_rad_s;
  const double diff = alpha2 * (u.left_m - u.right_m);
  const double l = alpha1 * u.left_m;
  const double r = alpha1 * u.right_m;
  *var_l_m2 = l * l + diff * diff;
  *var_r_m2 = r * r + diff * diff;
}

// Process noise R of one prediction step (eq. 1 or eq. 5), given the step's
// control Jacobian V.
inline StateCov process_noise(const NoiseParams& p, WheelTravel u, double abs_yaw_rate_rad_s,
                              const ControlJacobian& V) {
  if (p.model == NoiseModel::rq) {
    StateCov R = StateCov::Zero();
    R(kX, kX) = p.r_x_m2;
    R(kY, kY) = p.r_y_m2;
    R(kTheta, kTheta) = p.r_theta_rad2;
    return R;
  }
  double vl = 0.0, vr = 0.0;
  wheel_variances(p, u, abs_yaw_rate_rad_s, &vl, &vr);
  return vl * V.col(kLeft) * V.col(kLeft).transpose() + vr * V.col(kRight) * V.col(kRight).transpose();
}

}  // namespace odotune::filters

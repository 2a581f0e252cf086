#include <odotune/filters/dual_kf.h>

#include <Eigen/LU>  // fixed-size closed-form inverse()
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <odotune/core/why.h>

namespace odotune::filters {
namespace {

bool check(const char* name, double x, bool allow_zero, std::string* why) {
  if (std::isfinite(x) && (x > 0.0 || (allow_zero && x == 0.0))) return true;
  std::ostringstream os;
  os << name << " = " << x << " must be a finite number " << (allow_zero ? "≥ 0" : "> 0");
  return core::invalid(why, os.str());
}

// h(θ, ω): the odometry velocities (V, W) of parameters θ.
DkfVelocity odometry_velocity(const DkfParams& theta, double omega_l, double omega_r) {
  const double rr = omega_r * theta(kDkfRadiusRight);
  const double rl = omega_l * theta(kDkfRadiusLeft);
  return DkfVelocity(0.5 * (rr + rl), (rr - rl) / theta(kDkfWheelBase));
}

}  // namespace

bool DualKfParams::IsValid(std::string* why) const {
  std::string inner;
  if (!initial.IsValid(&inner)) {
    return core::invalid(why, "initial." + inner);
  }
  if (!evidence.IsValid(&inner)) {
    return core::invalid(why, "evidence." + inner);
  }
  return check("initial_sd_radius_m", initial_sd_radius_m, false, why) &&
         check("initial_sd_wheel_base_m", initial_sd_wheel_base_m, false, why) &&
         check("odometry_sd_v_m_s", odometry_sd_v_m_s, false, why) &&
         check("odometry_sd_w_rad_s", odometry_sd_w_rad_s, false, why) &&
         check("radius_walk_m_per_sqrt_s", radius_walk_m_per_sqrt_s, true, why) &&
         check("wheel_base_walk_m_per_sqrt_s", wheel_base_walk_m_per_sqrt_s, true, why);
}

DkfJacobian dkf_jacobian(const DkfParams& theta, double omega_l_rad_s, double omega_r_rad_s) {
  const double d = theta(kDkfWheelBase);
  DkfJacobian h;
  // V = (ω_r R_R + ω_l R_L)/2
  h(kDkfV, kDkfRadiusRight) = 0.5 * omega_r_rad_s;
  h(kDkfV, kDkfRadiusLeft) = 0.5 * omega_l_rad_s;
  h(kDkfV, kDkfWheelBase) = 0.0;
  // W = (ω_r R_R − ω_l R_L)/D
  h(kDkfW, kDkfRadiusRight) = omega_r_rad_s / d;
  h(kDkfW, kDkfRadiusLeft) = -omega_l_rad_s / d;
  h(kDkfW, kDkfWheelBase) = -(omega_r_rad_s * theta(kDkfRadiusRight) - omega_l_rad_s * theta(kDkfRadiusLeft)) /
                            (d * d);
  return h;
}

DualKf::DualKf(const DualKfParams& params) : params_(params), memory_(params.evidence) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("DualKfParams: " + why);
  theta_ << params.initial.wheel_radius_right_m, params.initial.wheel_radius_left_m,
      params.initial.wheel_base_m;
  const double sr2 = params.initial_sd_radius_m * params.initial_sd_radius_m;
  const double sd2 = params.initial_sd_wheel_base_m * params.initial_sd_wheel_base_m;
  P_theta_ = DkfParams(sr2, sr2, sd2).asDiagonal();
  estimate_.params = params.initial;
  estimate_.sd_radius_right_m = params.initial_sd_radius_m;
  estimate_.sd_radius_left_m = params.initial_sd_radius_m;
  estimate_.sd_wheel_base_m = params.initial_sd_wheel_base_m;
}

const CalibEstimate& DualKf::step(const CalibSample& s) {
  if (!(std::isfinite(s.dt_s) && s.dt_s >= 0.0) || !std::isfinite(s.omega_l_rad_s) ||
      !std::isfinite(s.omega_r_rad_s) || !std::isfinite(s.v_m_s) || !std::isfinite(s.w_rad_s) ||
      !(std::isfinite(s.v_var) && s.v_var > 0.0) || !(std::isfinite(s.w_var) && s.w_var > 0.0))
    throw std::invalid_argument("CalibSample: expected dt_s ≥ 0, finite rates and measurement, variances > 0");
  const double wl = s.omega_l_rad_s;
  const double wr = s.omega_r_rad_s;
  const DkfVelocity z(s.v_m_s, s.w_rad_s);
  const DkfVelocityCov p_odo = DkfVelocity(params_.odometry_sd_v_m_s * params_.odometry_sd_v_m_s,
                                           params_.odometry_sd_w_rad_s * params_.odometry_sd_w_rad_s)
                                   .asDiagonal();
  const DkfVelocityCov r_meas = DkfVelocity(s.v_var, s.w_var).asDiagonal();

  // State filter: prior x⁻ = h(θ̂, ω) with covariance P_odo, corrected by z.
  // Joseph form P = (I − K)P⁻(I − K)ᵀ + K R Kᵀ keeps P symmetric PD.
  const DkfVelocity x_prior = odometry_velocity(theta_, wl, wr);
  const DkfVelocityCov k_x = p_odo * (p_odo + r_meas).inverse();
  const DkfVelocity x_post = x_prior + k_x * (z - x_prior);
  const DkfVelocityCov i_k = DkfVelocityCov::Identity() - k_x;
  const DkfVelocityCov p_x = i_k * p_odo * i_k.transpose() + k_x * r_meas * k_x.transpose();

  // Parameter filter: random walk, then an EKF update with x̂ as the
  // measurement of h(θ, ω), H = ∂h/∂θ at θ⁻, covariance P_x + P_odo.
  const DkfJacobian h = dkf_jacobian(theta_, wl, wr);
  const DkfVelocityCov r_theta = p_x + p_odo;
  {
    // log p(z | past): z against the odometry's prediction h(θ̂, ω), with
    // the covariance it has before this step (H P_θ Hᵀ + P_odo + R).
    const DkfVelocityCov s_pred = h * P_theta_ * h.transpose() + p_odo + r_meas;
    const DkfVelocity e = z - x_prior;
    last_log_predictive_ = -0.5 * e.dot(s_pred.inverse() * e) - 0.5 * std::log(s_pred.determinant()) -
                           std::log(2.0 * std::numbers::pi);
  }
  DkfParamCov p_prior = P_theta_;
  if (params_.fading_memory) {
    // Fading memory (pf_evolution.h).
    const double inflate = memory_.step(s.dt_s);
    p_prior *= 1.0 + inflate;
    // Bounded: no variance grows past its initial value (no wind-up of a
    // direction the drive does not excite).
    const DkfParams p0(params_.initial_sd_radius_m * params_.initial_sd_radius_m,
                       params_.initial_sd_radius_m * params_.initial_sd_radius_m,
                       params_.initial_sd_wheel_base_m * params_.initial_sd_wheel_base_m);
    for (int k = 0; k < kDkfParamDim; ++k)
      if (p_prior(k, k) > p0(k)) {
        const double f = std::sqrt(p0(k) / p_prior(k, k));
        p_prior.row(k) *= f;
        p_prior.col(k) *= f;
      }
  } else {
    const double qr = params_.radius_walk_m_per_sqrt_s * params_.radius_walk_m_per_sqrt_s * s.dt_s;
    const double qd = params_.wheel_base_walk_m_per_sqrt_s * params_.wheel_base_walk_m_per_sqrt_s * s.dt_s;
    p_prior += DkfParamCov(DkfParams(qr, qr, qd).asDiagonal());
  }
  const DkfVelocityCov innovation_cov = h * p_prior * h.transpose() + r_theta;
  const Eigen::Matrix<double, kDkfParamDim, kDkfVelocityDim> k_theta = p_prior * h.transpose() *
                                                                       innovation_cov.inverse();
  theta_ += k_theta * (x_post - x_prior);  // x_prior = h(θ⁻, ω)
  const DkfParamCov i_kh = DkfParamCov::Identity() - k_theta * h;
  P_theta_ = i_kh * p_prior * i_kh.transpose() + k_theta * r_theta * k_theta.transpose();
  P_theta_ = (0.5 * (P_theta_ + P_theta_.transpose())).eval();

  ++iteration_;
  estimate_.params = {theta_(kDkfRadiusLeft), theta_(kDkfRadiusRight), theta_(kDkfWheelBase)};
  const DkfVelocity v_cal = odometry_velocity(theta_, wl, wr);
  estimate_.velocity = {v_cal(kDkfV), v_cal(kDkfW)};
  estimate_.sd_radius_right_m = std::sqrt(P_theta_(kDkfRadiusRight, kDkfRadiusRight));
  estimate_.sd_radius_left_m = std::sqrt(P_theta_(kDkfRadiusLeft, kDkfRadiusLeft));
  estimate_.sd_wheel_base_m = std::sqrt(P_theta_(kDkfWheelBase, kDkfWheelBase));
  return estimate_;
}

}  // namespace odotune::filters

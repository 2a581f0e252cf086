#include <odotune/calibration/batch_calibration.h>

#include <array>
#include <cmath>
#include <stdexcept>

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <odotune/calibration/ceres_fit.h>
#include <odotune/core/ceres_options.h>

namespace odotune::calibration {

namespace {

// Parameter block layout: θ = (R_R, R_L, D) [m], as in odotune/filters/dual_kf.h.
enum BatchParam : int { kRadiusRight = 0, kRadiusLeft = 1, kWheelBase = 2, kBatchParams = 3 };

// Huber scale in units of the measurement's σ (the residuals are whitened).
constexpr double kHuberScale = 3.0;
// Lower bound of every parameter as a fraction of its initial value: keeps
// D (and the radii) away from 0 without ever binding a plausible fit.
constexpr double kBatchLowerBoundFraction = 1e-2;

// Whitened velocity residuals of one calibration sample (header comment).
struct VelocityResidual {
  double omega_l, omega_r;  // [rad/s]
  double v_m, w_m;          // [m/s], [rad/s]
  double inv_sd_v, inv_sd_w;

  template <typename T>
  bool operator()(const T* theta, T* r) const {
    const T right = omega_r * theta[kRadiusRight];
    const T left = omega_l * theta[kRadiusLeft];
    r[0] = (0.5 * (right + left) - v_m) * inv_sd_v;
    r[1] = ((right - left) / theta[kWheelBase] - w_m) * inv_sd_w;
    return true;
  }
};

}  // namespace

BatchCalibrationSummary batch_calibrate(const std::vector<const CalibrationInput*>& inputs,
                                        const filters::OdometryParams& initial) {
  std::string why;
  if (!initial.IsValid(&why)) throw std::invalid_argument("batch calibration: initial parameters: " + why);
  std::string names;
  for (const CalibrationInput* in : inputs) {
    if (!in) throw std::invalid_argument("batch calibration: null input");
    names += fmt::format("{}'{}'", names.empty() ? "" : ", ", in->track_name);
  }

  double theta[kBatchParams];
  theta[kRadiusRight] = initial.wheel_radius_right_m;
  theta[kRadiusLeft] = initial.wheel_radius_left_m;
  theta[kWheelBase] = initial.wheel_base_m;

  ceres::Problem problem;
  // One loss shared by every block; the problem deletes it once.
  ceres::LossFunction* loss = new ceres::HuberLoss(kHuberScale);
  BatchCalibrationSummary out;
  for (const CalibrationInput* in : inputs)
    for (const filters::CalibSample& s : in->samples) {
      auto* f = new VelocityResidual{s.omega_l_rad_s, s.omega_r_rad_s,          s.v_m_s,
                                     s.w_rad_s,       1.0 / std::sqrt(s.v_var), 1.0 / std::sqrt(s.w_var)};
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<VelocityResidual, 2, kBatchParams>(f), loss,
                               theta);
      ++out.residual_pairs;
    }
  if (out.residual_pairs == 0) {
    delete loss;  // never handed to the problem
    throw std::invalid_argument(fmt::format(
        "batch calibration: the tracks {} hold no calibration sample (wheel rates + external velocity)",
        names.empty() ? "(none)" : names));
  }
  for (int i = 0; i < kBatchParams; ++i)
    problem.SetParameterLowerBound(theta, i, kBatchLowerBoundFraction * theta[i]);

  const ceres::Solver::Options so = core::deterministic_solver_options(100, core::FitTolerance::calibration);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.termination = summary.message;
  out.params.wheel_radius_right_m = theta[kRadiusRight];
  out.params.wheel_radius_left_m = theta[kRadiusLeft];
  out.params.wheel_base_m = theta[kWheelBase];

  // Standard errors: the covariance of the whitened problem, scaled by the
  // residual variance per degree of freedom s² = 2·cost/(2n − 3) (so that
  // they stay honest when the given variances are off, e.g. under encoder
  // quantisation noise in the wheel rates). NaN when D or a radius is
  // unobservable from the samples.
  const double dof = 2.0 * static_cast<double>(out.residual_pairs) - static_cast<double>(kBatchParams);
  const std::array<double, 3> sd = scaled_standard_errors(problem, theta, summary.final_cost, dof);
  out.sd_radius_right_m = sd[kRadiusRight];
  out.sd_radius_left_m = sd[kRadiusLeft];
  out.sd_wheel_base_m = sd[kWheelBase];
  return out;
}

}  // namespace odotune::calibration

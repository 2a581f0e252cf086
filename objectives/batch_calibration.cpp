#include "objectives/batch_calibration.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <fmt/format.h>

namespace odotune {

namespace {

// Parameter block layout: θ = (R_R, R_L, D) [m], as in filters/dual_kf.h.
enum BatchParam : int { kRadiusRight = 0, kRadiusLeft = 1, kWheelBase = 2, kBatchParams = 3 };

// Huber scale in units of the measurement's σ (the residuals are whitened).
constexpr double kHuberScale = 3.0;
// Lower bound of every parameter as a fraction of its initial value: keeps
// D (and the radii) away from 0 without ever binding a plausible fit.
constexpr double kLowerBoundFraction = 1e-2;
// Smallest eigenvalue ratio of the unit-diagonal-scaled JᵀJ for which the
// covariance is computed (below it a direction is unobservable, e.g. D on a
// track without turning).
constexpr double kMinEigenRatio = 1e-12;

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

// Whether the Jacobian at the solution has full column rank (judged on JᵀJ
// scaled to a unit diagonal, so units do not matter); checked before
// ceres::Covariance, which would log an error on a singular problem.
bool full_rank(ceres::Problem& problem) {
  ceres::CRSMatrix j;
  if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, nullptr, nullptr, &j)) return false;
  Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
  for (int row = 0; row < j.num_rows; ++row) {
    const auto b = static_cast<std::size_t>(j.rows[static_cast<std::size_t>(row)]);
    const auto e = static_cast<std::size_t>(j.rows[static_cast<std::size_t>(row) + 1]);
    for (std::size_t a = b; a < e; ++a)
      for (std::size_t c = b; c < e; ++c) jtj(j.cols[a], j.cols[c]) += j.values[a] * j.values[c];
  }
  const Eigen::Vector3d d = jtj.diagonal();
  if (!(d.array() > 0.0).all() || !d.allFinite()) return false;
  const Eigen::Vector3d inv = d.array().rsqrt();
  const Eigen::Matrix3d scaled = inv.asDiagonal() * jtj * inv.asDiagonal();
  const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scaled).eigenvalues();
  return ev.minCoeff() > kMinEigenRatio * ev.maxCoeff();
}

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
    problem.SetParameterLowerBound(theta, i, kLowerBoundFraction * theta[i]);

  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = 100;
  so.num_threads = 1;  // results independent of the machine
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.function_tolerance = 1e-12;
  so.gradient_tolerance = 1e-14;
  so.parameter_tolerance = 1e-12;
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
  const double nan = std::nan("");
  out.sd_radius_right_m = out.sd_radius_left_m = out.sd_wheel_base_m = nan;
  const double dof = 2.0 * static_cast<double>(out.residual_pairs) - static_cast<double>(kBatchParams);
  if (dof > 0.0 && full_rank(problem)) {
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.num_threads = 1;
    ceres::Covariance cov(co);
    const std::vector<std::pair<const double*, const double*>> blocks = {{theta, theta}};
    double c[kBatchParams * kBatchParams];
    if (cov.Compute(blocks, &problem) && cov.GetCovarianceBlock(theta, theta, c)) {
      const double s2 = 2.0 * summary.final_cost / dof;
      auto sd = [&](int i) { return std::sqrt(c[i * kBatchParams + i] * s2); };
      out.sd_radius_right_m = sd(kRadiusRight);
      out.sd_radius_left_m = sd(kRadiusLeft);
      out.sd_wheel_base_m = sd(kWheelBase);
    }
  }
  return out;
}

}  // namespace odotune

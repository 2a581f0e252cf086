#include "calibration/ceres_fit.h"

#include <cmath>
#include <vector>

#include <Eigen/Dense>

namespace odotune {

namespace {

// Smallest eigenvalue ratio of the unit-diagonal-scaled JᵀJ for which the
// covariance is computed (below it a direction is unobservable).
constexpr double kMinEigenRatio = 1e-12;

// Whether the Jacobian columns of `theta` have full rank at the solution.
bool full_rank(ceres::Problem& problem, double* theta) {
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = {theta};  // the other blocks are held as they are
  ceres::CRSMatrix j;
  if (!problem.Evaluate(eo, nullptr, nullptr, nullptr, &j)) return false;
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

std::array<double, 3> scaled_standard_errors(ceres::Problem& problem, double* theta, double final_cost,
                                             double dof) {
  const double nan = std::nan("");
  std::array<double, 3> out{nan, nan, nan};
  if (!(dof > 0.0) || !full_rank(problem, theta)) return out;
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.num_threads = 1;
  ceres::Covariance cov(co);
  const std::vector<std::pair<const double*, const double*>> blocks = {{theta, theta}};
  double c[9];
  if (!cov.Compute(blocks, &problem) || !cov.GetCovarianceBlock(theta, theta, c)) return out;
  const double s2 = 2.0 * final_cost / dof;
  for (int i = 0; i < 3; ++i)
    if (c[i * 3 + i] > 0.0) out[static_cast<std::size_t>(i)] = std::sqrt(c[i * 3 + i] * s2);
  return out;
}

}  // namespace odotune

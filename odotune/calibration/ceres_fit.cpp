#include <odotune/calibration/ceres_fit.h>

#include <cmath>
#include <vector>

#include <Eigen/Dense>

namespace odotune::calibration {

namespace {

// Smallest eigenvalue ratio of the unit-diagonal-scaled JᵀJ for which the
// covariance is computed (below it a direction is unobservable).
constexpr double kMinEigenRatio = 1e-12;

// Whether the Jacobian columns of `theta` (n entries) have full rank at the solution.
bool full_rank(ceres::Problem& problem, double* theta, int n) {
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = {theta};  // the other blocks are held as they are
  ceres::CRSMatrix j;
  if (!problem.Evaluate(eo, nullptr, nullptr, nullptr, &j)) return false;
  Eigen::MatrixXd jtj = Eigen::MatrixXd::Zero(n, n);
  for (int row = 0; row < j.num_rows; ++row) {
    const auto b = static_cast<std::size_t>(j.rows[static_cast<std::size_t>(row)]);
    const auto e = static_cast<std::size_t>(j.rows[static_cast<std::size_t>(row) + 1]);
    for (std::size_t a = b; a < e; ++a)
      for (std::size_t c = b; c < e; ++c) jtj(j.cols[a], j.cols[c]) += j.values[a] * j.values[c];
  }
  const Eigen::VectorXd d = jtj.diagonal();
  if (!(d.array() > 0.0).all() || !d.allFinite()) return false;
  const Eigen::VectorXd inv = d.array().rsqrt();
  const Eigen::MatrixXd scaled = inv.asDiagonal() * jtj * inv.asDiagonal();
  const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scaled).eigenvalues();
  return ev.minCoeff() > kMinEigenRatio * ev.maxCoeff();
}

}  // namespace

std::vector<double> scaled_standard_errors(ceres::Problem& problem, double* theta, int n, double final_cost,
                                           double dof) {
  const auto m = static_cast<std::size_t>(n);
  std::vector<double> out(m, std::nan(""));
  if (!(dof > 0.0) || !full_rank(problem, theta, n)) return out;
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.num_threads = 1;
  ceres::Covariance cov(co);
  const std::vector<std::pair<const double*, const double*>> blocks = {{theta, theta}};
  std::vector<double> c(m * m);
  if (!cov.Compute(blocks, &problem) || !cov.GetCovarianceBlock(theta, theta, c.data())) return out;
  const double s2 = 2.0 * final_cost / dof;
  for (std::size_t i = 0; i < m; ++i) {
    const double v = c[i * m + i];
    if (v > 0.0) out[i] = std::sqrt(v * s2);
  }
  return out;
}

std::array<double, 3> scaled_standard_errors(ceres::Problem& problem, double* theta, double final_cost,
                                             double dof) {
  const std::vector<double> sd = scaled_standard_errors(problem, theta, 3, final_cost, dof);
  return {sd[0], sd[1], sd[2]};
}

}  // namespace odotune::calibration

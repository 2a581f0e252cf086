#include <odotune/objectives/rl_innovations.h>

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>

namespace odotune::objectives {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// eᵀC⁻¹e and ln det C of a 2 × 2 covariance; false when C is not positive definite.
bool quadratic(const Eigen::Vector2d& e, const Eigen::Matrix2d& C, double* q, double* logdet) {
  const Eigen::LLT<Eigen::Matrix2d> llt(C);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::Vector2d w = llt.matrixL().solve(e);
  *q = w.squaredNorm();
  *logdet = 2.0 * std::log(llt.matrixL()(0, 0) * llt.matrixL()(1, 1));
  return std::isfinite(*q) && std::isfinite(*logdet);
}

double mean_nis(std::span<const rlnode::Innovation> v) {
  double sum = 0.0;
  for (const rlnode::Innovation& i : v) {
    double q = 0.0, ld = 0.0;
    if (!quadratic(i.nu, i.S, &q, &ld)) return kNaN;
    sum += q;
  }
  return v.empty() ? kNaN : sum / static_cast<double>(v.size());
}

}  // namespace

double innovation_nll(std::span<const rlnode::Innovation> v) {
  double sum = 0.0;
  for (const rlnode::Innovation& i : v) {
    double q = 0.0, ld = 0.0;
    if (!quadratic(i.nu, i.S, &q, &ld)) return kNaN;
    sum += q + ld;
  }
  return v.empty() ? kNaN : sum / static_cast<double>(v.size());
}

double nis_cost(std::span<const rlnode::Innovation> v) { return std::abs(std::log(mean_nis(v) / 2.0)); }

double whiteness_cost(std::span<const rlnode::Innovation> v, int lags) {
  // Whitened innovations w_k = L_k⁻¹ν_k (S_k = L_k·L_kᵀ): unit covariance when consistent.
  std::vector<Eigen::Vector2d> w;
  for (const rlnode::Innovation& i : v) {
    const Eigen::LLT<Eigen::Matrix2d> llt(i.S);
    if (llt.info() != Eigen::Success) return kNaN;
    w.push_back(llt.matrixL().solve(i.nu));
  }
  const std::size_t n = w.size();
  if (n <= static_cast<std::size_t>(lags) + 1) return kNaN;
  double c0 = 0.0;
  for (const Eigen::Vector2d& e : w) c0 += e.squaredNorm();
  double cost = std::pow(std::log(c0 / static_cast<double>(n) / 2.0), 2);
  for (int j = 1; j <= lags; ++j) {
    double cj = 0.0;
    for (std::size_t k = 0; k + static_cast<std::size_t>(j) < n; ++k) cj += w[k].dot(w[k + j]);
    cost += (cj / c0) * (cj / c0);
  }
  return std::isfinite(cost) ? cost : kNaN;
}

double heldout_nll(std::span<const rlnode::ReplayOutput> outputs) {
  double sum = 0.0;
  long n = 0;
  for (const rlnode::ReplayOutput& o : outputs) {
    for (const rlnode::ScoredFix& f : o.scored) {
      double q = 0.0, ld = 0.0;
      if (!quadratic((f.measured - f.predicted).head<2>(), f.predicted_cov + f.fix_cov, &q, &ld)) return kNaN;
      sum += q + ld;
      ++n;
    }
  }
  return n > 0 ? sum / static_cast<double>(n) : kNaN;
}

}  // namespace odotune::objectives

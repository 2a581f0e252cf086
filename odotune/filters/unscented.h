// The scaled unscented transform of Wan & van der Merwe, "The Unscented
// Kalman Filter for Nonlinear Estimation" (2000), for an N-dimensional state
// on fixed-size Eigen types: the weights (eq. 15), the sigma points and the
// measurement update (eqs. 17). Shared by the fusion filters
// (velocity_ukf.h, pose_velocity_ukf.h). Header-only; no I/O.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>

#include <odotune/core/why.h>

namespace odotune::filters::unscented {

// The transform's parameters as the weights below need them: α in (0, 1],
// β ≥ 0, n + κ > 0. False with "alpha = 2 must be in (0, 1]" in *why.
template <int N>
bool parameters_valid(double alpha, double beta, double kappa, std::string* why) {
  const auto out_of_range = [why](const char* name, double x, const std::string& expected) {
    std::ostringstream os;
    os << name << " = " << x << " must be " << expected;
    return core::invalid(why, os.str());
  };
  if (!(std::isfinite(alpha) && alpha > 0.0 && alpha <= 1.0)) return out_of_range("alpha", alpha, "in (0, 1]");
  if (!(std::isfinite(beta) && beta >= 0.0)) return out_of_range("beta", beta, "a finite number >= 0");
  if (!(std::isfinite(kappa) && static_cast<double>(N) + kappa > 0.0))
    return out_of_range("kappa", kappa, "finite with n + kappa > 0 (n = " + std::to_string(N) + ")");
  return true;
}

template <int N>
struct SigmaWeights {
  static constexpr int kSigma = 2 * N + 1;
  double lambda = 0.0;
  std::array<double, kSigma> wm{}, wc{};
};

// λ = α²(n + κ) − n,  W₀^(m) = λ/(n + λ),  W₀^(c) = λ/(n + λ) + (1 − α² + β),
// W_i^(m) = W_i^(c) = 1/(2(n + λ)), i = 1..2n.
template <int N>
SigmaWeights<N> sigma_weights(double alpha, double beta, double kappa) {
  SigmaWeights<N> w;
  const double n = static_cast<double>(N);
  w.lambda = alpha * alpha * (n + kappa) - n;
  const double n_lambda = n + w.lambda;
  w.wm[0] = w.lambda / n_lambda;
  w.wc[0] = w.wm[0] + (1.0 - alpha * alpha + beta);
  for (int i = 1; i < SigmaWeights<N>::kSigma; ++i)
    w.wm[static_cast<std::size_t>(i)] = w.wc[static_cast<std::size_t>(i)] = 0.5 / n_lambda;
  return w;
}

template <int N>
using SigmaPoints = Eigen::Matrix<double, N, 2 * N + 1>;

// χ₀ = x̄, χ_i = x̄ + (√((n+λ)P))_i, χ_{n+i} = x̄ − (√((n+λ)P))_i (columns
// of the lower Cholesky factor). False when P is not positive definite.
template <int N>
bool sigma_points(const Eigen::Matrix<double, N, 1>& x, const Eigen::Matrix<double, N, N>& P, double lambda,
                  SigmaPoints<N>* chi) {
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt((static_cast<double>(N) + lambda) * P);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::Matrix<double, N, N> L = llt.matrixL();
  chi->col(0) = x;
  for (int i = 0; i < N; ++i) {
    chi->col(1 + i) = x + L.col(i);
    chi->col(1 + N + i) = x - L.col(i);
  }
  return true;
}

// The measurement update for z = h(x) + r, r ~ N(0, R):
//   Z_i = h(χ_i),  ẑ = Σ W^(m) Z_i,  S = Σ W^(c) (Z_i − ẑ)(Z_i − ẑ)ᵀ + R,
//   P_xz = Σ W^(c) (χ_i − x̄)(Z_i − ẑ)ᵀ,  K = P_xz S⁻¹,
//   x ← x + K (z − ẑ),  P ← P − K S Kᵀ (symmetrised).
// False when P or S is not positive definite or the result is not finite
// (x and P are then left as they are or partly updated: the caller marks the
// filter unhealthy).
template <int N, int M, typename Measure>
bool update(const SigmaWeights<N>& w, Eigen::Matrix<double, N, 1>* x, Eigen::Matrix<double, N, N>* P,
            const Eigen::Matrix<double, M, 1>& z, const Eigen::Matrix<double, M, M>& R, Measure&& h) {
  using Vec = Eigen::Matrix<double, M, 1>;
  using Mat = Eigen::Matrix<double, M, M>;
  constexpr int kSigma = SigmaWeights<N>::kSigma;
  SigmaPoints<N> chi;
  if (!sigma_points<N>(*x, *P, w.lambda, &chi)) return false;
  Eigen::Matrix<double, M, kSigma> Z;
  for (int i = 0; i < kSigma; ++i) Z.col(i) = h(Eigen::Matrix<double, N, 1>(chi.col(i)));
  Vec z_hat = Vec::Zero();
  for (int i = 0; i < kSigma; ++i) z_hat += w.wm[static_cast<std::size_t>(i)] * Z.col(i);
  Mat S = R;
  Eigen::Matrix<double, N, M> Pxz = Eigen::Matrix<double, N, M>::Zero();
  for (int i = 0; i < kSigma; ++i) {
    const double wc = w.wc[static_cast<std::size_t>(i)];
    const Vec dz = Z.col(i) - z_hat;
    S += wc * dz * dz.transpose();
    Pxz += wc * (chi.col(i) - *x) * dz.transpose();
  }
  const Eigen::LLT<Mat> llt(S);
  if (llt.info() != Eigen::Success) return false;
  // K = P_xz S⁻¹ = (S⁻¹ P_xzᵀ)ᵀ (S symmetric).
  const Eigen::Matrix<double, N, M> K = llt.solve(Pxz.transpose()).transpose();
  *x += K * (z - z_hat);
  const Eigen::Matrix<double, N, N> P_new = *P - K * S * K.transpose();
  *P = 0.5 * (P_new + P_new.transpose());
  return x->allFinite() && P->allFinite();
}

}  // namespace odotune::filters::unscented

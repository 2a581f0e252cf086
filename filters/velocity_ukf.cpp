#include "filters/velocity_ukf.h"

#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace odotune::filters {
namespace {

constexpr int kN = 2;               // state dimension n
constexpr int kSigma = 2 * kN + 1;  // 2n + 1 sigma points

std::string describe(const char* name, double x, const char* expected) {
  std::ostringstream os;
  os << name << " = " << x << " must be " << expected;
  return os.str();
}

bool bad(std::string* why, const std::string& msg) {
  if (why) *why = msg;
  return false;
}

bool is_spd(const Eigen::Matrix2d& M) {
  if (!M.allFinite()) return false;
  if (M(0, 1) != M(1, 0)) {
    // Allow rounding-level asymmetry only.
    const double scale = std::abs(M(0, 1)) + std::abs(M(1, 0));
    if (std::abs(M(0, 1) - M(1, 0)) > 1e-12 * scale) return false;
  }
  return M(0, 0) > 0.0 && M(1, 1) > 0.0 && M(0, 0) * M(1, 1) - M(0, 1) * M(1, 0) > 0.0;
}

// Weights of the scaled unscented transform (Wan & van der Merwe 2000,
// eq. 15): λ = α²(n + κ) − n,
//   W₀^(m) = λ/(n + λ),  W₀^(c) = λ/(n + λ) + (1 − α² + β),
//   W_i^(m) = W_i^(c) = 1/(2(n + λ)),  i = 1..2n.
struct SigmaWeights {
  double lambda = 0.0;
  std::array<double, kSigma> wm{}, wc{};
};

SigmaWeights sigma_weights(const UkfParams& p) {
  SigmaWeights w;
  const double n = static_cast<double>(kN);
  w.lambda = p.alpha * p.alpha * (n + p.kappa) - n;
  const double n_lambda = n + w.lambda;
  w.wm[0] = w.lambda / n_lambda;
  w.wc[0] = w.wm[0] + (1.0 - p.alpha * p.alpha + p.beta);
  for (int i = 1; i < kSigma; ++i)
    w.wm[static_cast<std::size_t>(i)] = w.wc[static_cast<std::size_t>(i)] = 0.5 / n_lambda;
  return w;
}

using SigmaPoints = Eigen::Matrix<double, kN, kSigma>;

// χ₀ = x̄, χ_i = x̄ + (√((n+λ)P))_i, χ_{n+i} = x̄ − (√((n+λ)P))_i (columns
// of the lower Cholesky factor). False when P is not positive definite.
bool sigma_points(const Velocity& x, const VelocityCov& P, double lambda, SigmaPoints* chi) {
  const Eigen::LLT<VelocityCov> llt((static_cast<double>(kN) + lambda) * P);
  if (llt.info() != Eigen::Success) return false;
  const VelocityCov L = llt.matrixL();
  chi->col(0) = x;
  for (int i = 0; i < kN; ++i) {
    chi->col(1 + i) = x + L.col(i);
    chi->col(1 + kN + i) = x - L.col(i);
  }
  return true;
}

}  // namespace

bool UkfParams::IsValid(std::string* why) const {
  if (!(std::isfinite(q_v_m2_s3) && q_v_m2_s3 >= 0.0))
    return bad(why, describe("q_v_m2_s3", q_v_m2_s3, "a finite number >= 0 [(m/s)^2/s]"));
  if (!(std::isfinite(q_w_rad2_s3) && q_w_rad2_s3 >= 0.0))
    return bad(why, describe("q_w_rad2_s3", q_w_rad2_s3, "a finite number >= 0 [(rad/s)^2/s]"));
  if (!(std::isfinite(alpha) && alpha > 0.0 && alpha <= 1.0))
    return bad(why, describe("alpha", alpha, "in (0, 1]"));
  if (!(std::isfinite(beta) && beta >= 0.0)) return bad(why, describe("beta", beta, "a finite number >= 0"));
  if (!(std::isfinite(kappa) && static_cast<double>(kN) + kappa > 0.0))
    return bad(why, describe("kappa", kappa, "finite with n + kappa > 0 (n = 2)"));
  if (!initial_state.allFinite()) return bad(why, "initial_state must be finite");
  if (!is_spd(initial_cov)) return bad(why, "initial_cov must be symmetric positive definite");
  return true;
}

VelocityUkf::VelocityUkf(const UkfParams& params) : p_(params) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("UkfParams: " + why);
  x_ = params.initial_state;
  P_ = params.initial_cov;
}

void VelocityUkf::predict(double dt_s) {
  if (!healthy_) return;
  if (!(std::isfinite(dt_s) && dt_s >= 0.0)) {
    healthy_ = false;
    return;
  }
  const SigmaWeights w = sigma_weights(p_);
  SigmaPoints chi;
  if (!sigma_points(x_, P_, w.lambda, &chi)) {
    healthy_ = false;
    return;
  }
  // f(χ) = χ: "uniform rectilinear motion", constant (V, W) (paper §1).
  const SigmaPoints chi_pred = chi;
  Velocity x_pred = Velocity::Zero();
  for (int i = 0; i < kSigma; ++i) x_pred += w.wm[static_cast<std::size_t>(i)] * chi_pred.col(i);
  VelocityCov P_pred = VelocityCov::Zero();
  for (int i = 0; i < kSigma; ++i) {
    const Velocity d = chi_pred.col(i) - x_pred;
    P_pred += w.wc[static_cast<std::size_t>(i)] * d * d.transpose();
  }
  // Q·Δt: white-noise accelerations of spectral density q (a random walk).
  P_pred(kV, kV) += p_.q_v_m2_s3 * dt_s;
  P_pred(kW, kW) += p_.q_w_rad2_s3 * dt_s;
  x_ = x_pred;
  P_ = 0.5 * (P_pred + P_pred.transpose());
  if (!x_.allFinite() || !is_spd(P_)) healthy_ = false;
}

namespace {

// The unscented measurement update for h(χ) = H χ with the rows of H picked
// by `Rows` (a full (V, W) measurement or W alone), eqs. 17 of Wan & van der
// Merwe 2000:
//   Z_i = h(χ_i),  ẑ = Σ W^(m) Z_i,  S = Σ W^(c) (Z_i − ẑ)(Z_i − ẑ)ᵀ + R,
//   P_xz = Σ W^(c) (χ_i − x̄)(Z_i − ẑ)ᵀ,  K = P_xz S⁻¹,
//   x ← x + K (z − ẑ),  P ← P − K S Kᵀ.
template <int M, typename Measure>
bool unscented_update(const UkfParams& p, Velocity* x, VelocityCov* P, const Eigen::Matrix<double, M, 1>& z,
                      const Eigen::Matrix<double, M, M>& R, Measure&& h) {
  using Vec = Eigen::Matrix<double, M, 1>;
  using Mat = Eigen::Matrix<double, M, M>;
  const SigmaWeights w = sigma_weights(p);
  SigmaPoints chi;
  if (!sigma_points(*x, *P, w.lambda, &chi)) return false;
  Eigen::Matrix<double, M, kSigma> Z;
  for (int i = 0; i < kSigma; ++i) Z.col(i) = h(Velocity(chi.col(i)));
  Vec z_hat = Vec::Zero();
  for (int i = 0; i < kSigma; ++i) z_hat += w.wm[static_cast<std::size_t>(i)] * Z.col(i);
  Mat S = R;
  Eigen::Matrix<double, kN, M> Pxz = Eigen::Matrix<double, kN, M>::Zero();
  for (int i = 0; i < kSigma; ++i) {
    const double wc = w.wc[static_cast<std::size_t>(i)];
    const Vec dz = Z.col(i) - z_hat;
    S += wc * dz * dz.transpose();
    Pxz += wc * (chi.col(i) - *x) * dz.transpose();
  }
  const Eigen::LLT<Mat> llt(S);
  if (llt.info() != Eigen::Success) return false;
  // K = P_xz S⁻¹ = (S⁻¹ P_xzᵀ)ᵀ (S symmetric).
  const Eigen::Matrix<double, kN, M> K = llt.solve(Pxz.transpose()).transpose();
  *x += K * (z - z_hat);
  const VelocityCov P_new = *P - K * S * K.transpose();
  *P = 0.5 * (P_new + P_new.transpose());
  return x->allFinite() && is_spd(*P);
}

}  // namespace

void VelocityUkf::update(const Velocity& z, const VelocityCov& R) {
  if (!healthy_) return;
  if (!z.allFinite() || !is_spd(R)) {
    healthy_ = false;
    return;
  }
  // Odometry and the external sensor observe the state directly: h(x) = x.
  healthy_ = unscented_update<2>(p_, &x_, &P_, z, R, [](const Velocity& s) { return s; });
}

void VelocityUkf::update_yaw_rate(double w_rad_s, double var) {
  if (!healthy_) return;
  if (!std::isfinite(w_rad_s) || !(std::isfinite(var) && var > 0.0)) {
    healthy_ = false;
    return;
  }
  // The gyro observes W: h(x) = x(kW).
  const Eigen::Matrix<double, 1, 1> z(w_rad_s);
  const Eigen::Matrix<double, 1, 1> R(var);
  healthy_ = unscented_update<1>(p_, &x_, &P_, z, R,
                                 [](const Velocity& s) { return Eigen::Matrix<double, 1, 1>(s(kW)); });
}

PlanarPose integrate_pose(const PlanarPose& pose, double v_m_s, double w_rad_s, double dt_s) {
  // Paper eq. 3: the position advances along the heading at the START of
  // the step, then the heading turns.
  PlanarPose next;
  next.theta_rad = pose.theta_rad + w_rad_s * dt_s;
  next.x_m = pose.x_m + v_m_s * std::cos(pose.theta_rad) * dt_s;
  next.y_m = pose.y_m + v_m_s * std::sin(pose.theta_rad) * dt_s;
  return next;
}

double nees(const Velocity& truth, const Velocity& estimate, const VelocityCov& P) {
  if (!is_spd(P)) return std::nan("");
  const Eigen::LLT<VelocityCov> llt(P);
  if (llt.info() != Eigen::Success) return std::nan("");
  const Velocity e = truth - estimate;
  return e.dot(llt.solve(e));
}

}  // namespace odotune::filters

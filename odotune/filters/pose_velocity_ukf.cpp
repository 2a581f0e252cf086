#include <odotune/filters/pose_velocity_ukf.h>

#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <odotune/core/why.h>
#include <odotune/filters/unscented.h>

namespace odotune::filters {
namespace {

constexpr int kPvN = 5;

std::string describe_pv(const char* name, double x, const char* expected) {
  std::ostringstream os;
  os << name << " = " << x << " must be " << expected;
  return os.str();
}

template <int N>
bool is_spd_pv(const Eigen::Matrix<double, N, N>& M) {
  if (!M.allFinite()) return false;
  if (!M.isApprox(M.transpose(), 1e-12)) return false;
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(M);
  return llt.info() == Eigen::Success;
}

// The unicycle over dt with the midpoint heading (the header's model).
PoseVelocity motion(const PoseVelocity& s, double dt) {
  PoseVelocity n = s;
  const double mid = s(kPtheta) + 0.5 * s(kPw) * dt;
  n(kPx) += s(kPv) * dt * std::cos(mid);
  n(kPy) += s(kPv) * dt * std::sin(mid);
  n(kPtheta) += s(kPw) * dt;
  return n;
}

}  // namespace

bool PoseUkfParams::IsValid(std::string* why) const {
  for (const auto& [name, q] : {std::pair{"q_v_m2_s3", q_v_m2_s3}, std::pair{"q_w_rad2_s3", q_w_rad2_s3},
                                std::pair{"q_xy_m2_s", q_xy_m2_s}})
    if (!(std::isfinite(q) && q >= 0.0))
      return core::invalid(why, describe_pv(name, q, "a finite number >= 0"));
  if (!unscented::parameters_valid<kPvN>(alpha, beta, kappa, why)) return false;
  if (!initial_state.allFinite()) return core::invalid(why, "initial_state must be finite");
  if (!is_spd_pv<kPvN>(initial_cov))
    return core::invalid(why, "initial_cov must be symmetric positive definite");
  return true;
}

PoseVelocityUkf::PoseVelocityUkf(const PoseUkfParams& params) : p_(params) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("PoseUkfParams: " + why);
  x_ = params.initial_state;
  P_ = params.initial_cov;
}

void PoseVelocityUkf::predict(double dt_s) {
  if (!healthy_) return;
  if (!(std::isfinite(dt_s) && dt_s >= 0.0)) {
    healthy_ = false;
    return;
  }
  const auto w = unscented::sigma_weights<kPvN>(p_.alpha, p_.beta, p_.kappa);
  unscented::SigmaPoints<kPvN> chi;
  if (!unscented::sigma_points<kPvN>(x_, P_, w.lambda, &chi)) {
    healthy_ = false;
    return;
  }
  constexpr int kSigma = unscented::SigmaWeights<kPvN>::kSigma;
  for (int i = 0; i < kSigma; ++i) chi.col(i) = motion(chi.col(i), dt_s);
  PoseVelocity x = PoseVelocity::Zero();
  for (int i = 0; i < kSigma; ++i) x += w.wm[static_cast<std::size_t>(i)] * chi.col(i);
  PoseVelocityCov P = PoseVelocityCov::Zero();
  for (int i = 0; i < kSigma; ++i) {
    const PoseVelocity d = chi.col(i) - x;
    P += w.wc[static_cast<std::size_t>(i)] * d * d.transpose();
  }
  P(kPv, kPv) += p_.q_v_m2_s3 * dt_s;
  P(kPw, kPw) += p_.q_w_rad2_s3 * dt_s;
  P(kPx, kPx) += p_.q_xy_m2_s * dt_s;
  P(kPy, kPy) += p_.q_xy_m2_s * dt_s;
  x_ = x;
  P_ = 0.5 * (P + P.transpose());
  if (!x_.allFinite() || !is_spd_pv<kPvN>(P_)) healthy_ = false;
}

namespace {

// The Kalman update of a measurement picking `rows` of the state.
template <int M>
bool linear_update(PoseVelocity* x, PoseVelocityCov* P, const Eigen::Matrix<double, M, 1>& z,
                   const Eigen::Matrix<double, M, M>& R, const std::array<int, M>& rows) {
  if (!z.allFinite() || !is_spd_pv<M>(R)) return false;
  Eigen::Matrix<double, M, kPvN> H = Eigen::Matrix<double, M, kPvN>::Zero();
  for (int r = 0; r < M; ++r) H(r, rows[static_cast<std::size_t>(r)]) = 1.0;
  const Eigen::Matrix<double, M, M> S = H * *P * H.transpose() + R;
  const Eigen::LLT<Eigen::Matrix<double, M, M>> llt(S);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::Matrix<double, kPvN, M> K = llt.solve(H * *P).transpose();  // P Hᵀ S⁻¹ (P, S symmetric)
  *x += K * (z - H * *x);
  // Joseph form: (I − KH) P (I − KH)ᵀ + K R Kᵀ, symmetric and positive by construction.
  const PoseVelocityCov I_KH = PoseVelocityCov::Identity() - K * H;
  const PoseVelocityCov P_new = I_KH * *P * I_KH.transpose() + K * R * K.transpose();
  *P = 0.5 * (P_new + P_new.transpose());
  return x->allFinite() && is_spd_pv<kPvN>(*P);
}

}  // namespace

void PoseVelocityUkf::update_velocity(double v_m_s, double w_rad_s, const Eigen::Matrix2d& R) {
  if (healthy_) healthy_ = linear_update<2>(&x_, &P_, Eigen::Vector2d(v_m_s, w_rad_s), R, {kPv, kPw});
}

void PoseVelocityUkf::update_yaw_rate(double w_rad_s, double var) {
  if (healthy_)
    healthy_ = linear_update<1>(&x_, &P_, Eigen::Matrix<double, 1, 1>(w_rad_s),
                                Eigen::Matrix<double, 1, 1>(var), {kPw});
}

void PoseVelocityUkf::update_position(double x_m, double y_m, const Eigen::Matrix2d& R) {
  if (healthy_) healthy_ = linear_update<2>(&x_, &P_, Eigen::Vector2d(x_m, y_m), R, {kPx, kPy});
}

}  // namespace odotune::filters

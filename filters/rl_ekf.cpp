#include "filters/rl_ekf.h"

#include <cmath>
#include <numbers>
#include <utility>

#include <Eigen/LU>
#include <fmt/format.h>

namespace odotune::filters::rl {
namespace {

// The model's matrices are the identity plus a few terms: A has 28 of them
// and J 13 more. The hot path works on that list instead of dense 15 × 15
// products (J·P·Jᵀ in about 1 200 multiplications instead of 6 750).
struct Term {
  int row, col;
  double value;
};
struct OffIdentity {
  std::array<Term, 41> terms{};
  int size = 0;
  void add(int r, int c, double v) { terms[size++] = {r, c, v}; }
};

// A − I (first 28 terms) followed by J − A (the Jacobian's extra terms):
// ekf.cpp's transfer function and its analytic Jacobian.
OffIdentity model_terms(const State& x, double dt) {
  const double sr = std::sin(x[kRoll]), cr = std::cos(x[kRoll]);
  const double sp = std::sin(x[kPitch]), cp = std::cos(x[kPitch]);
  const double sy = std::sin(x[kYaw]), cy = std::cos(x[kYaw]);
  const double cpi = 1.0 / cp, tp = sp * cpi;
  const double half_dt2 = 0.5 * dt * dt;
  // Body → world rotation R(roll, pitch, yaw), row by row.
  const double rot[3][3] = {{cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
                            {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
                            {-sp, cp * sr, cp * cr}};
  OffIdentity t;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      t.add(kX + i, kVx + j, rot[i][j] * dt);
      t.add(kX + i, kAx + j, 0.5 * rot[i][j] * dt * dt);
    }
  }
  t.add(kRoll, kVroll, dt);
  t.add(kRoll, kVpitch, sr * tp * dt);
  t.add(kRoll, kVyaw, cr * tp * dt);
  t.add(kPitch, kVpitch, cr * dt);
  t.add(kPitch, kVyaw, -sr * dt);
  t.add(kYaw, kVpitch, sr * cpi * dt);
  t.add(kYaw, kVyaw, cr * cpi * dt);
  for (int i = 0; i < 3; ++i) t.add(kVx + i, kAx + i, dt);

  // ∂(R·(v·dt + a·dt²/2))/∂(roll, pitch, yaw): each is a rotation derivative
  // applied to w = v·dt + a·dt²/2.
  const double w[3] = {x[kVx] * dt + x[kAx] * half_dt2, x[kVy] * dt + x[kAy] * half_dt2,
                       x[kVz] * dt + x[kAz] * half_dt2};
  auto dot = [&w](double a, double b, double c) { return a * w[0] + b * w[1] + c * w[2]; };
  t.add(kX, kRoll, dot(0.0, cy * sp * cr + sy * sr, -cy * sp * sr + sy * cr));
  t.add(kX, kPitch, dot(-cy * sp, cy * cp * sr, cy * cp * cr));
  t.add(kX, kYaw, dot(-sy * cp, -sy * sp * sr - cy * cr, -sy * sp * cr + cy * sr));
  t.add(kY, kRoll, dot(0.0, sy * sp * cr - cy * sr, -sy * sp * sr - cy * cr));
  t.add(kY, kPitch, dot(-sy * sp, sy * cp * sr, sy * cp * cr));
  t.add(kY, kYaw, dot(cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr));
  t.add(kZ, kRoll, dot(0.0, cp * cr, -cp * sr));
  t.add(kZ, kPitch, dot(-cp, -sp * sr, -sp * cr));
  const double vp = x[kVpitch], vy = x[kVyaw];
  t.add(kRoll, kRoll, (cr * tp * vp - sr * tp * vy) * dt);
  t.add(kRoll, kPitch, (cpi * cpi * sr * vp + cpi * cpi * cr * vy) * dt);
  t.add(kPitch, kRoll, (-sr * vp - cr * vy) * dt);
  t.add(kYaw, kRoll, (cr * cpi * vp - sr * cpi * vy) * dt);
  t.add(kYaw, kPitch, (sr * tp * cpi * vp + cr * tp * cpi * vy) * dt);
  return t;
}

constexpr int kTransferTerms = 28;

void wrap_angles(State& x) {
  x[kRoll] = normalize_angle(x[kRoll]);
  x[kPitch] = normalize_angle(x[kPitch]);
  x[kYaw] = normalize_angle(x[kYaw]);
}

bool is_angle(int member) { return member == kRoll || member == kPitch || member == kYaw; }

}  // namespace

double normalize_angle(double a) {
  const double r = std::fmod(a + std::numbers::pi, 2.0 * std::numbers::pi);
  return r <= 0.0 ? r + std::numbers::pi : r - std::numbers::pi;
}

Transition transition(const State& x, double dt_s) {
  const OffIdentity t = model_terms(x, dt_s);
  Transition out{Cov::Identity(), Cov::Identity()};
  for (int k = 0; k < t.size; ++k) {
    const Term& e = t.terms[k];
    if (k < kTransferTerms) out.A(e.row, e.col) += e.value;
    out.J(e.row, e.col) += e.value;
  }
  return out;
}

bool RlEkfParams::IsValid(std::string* why) const {
  auto fail = [why](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (!process_noise.allFinite()) return fail("process_noise has a non-finite entry");
  if (!initial_cov.allFinite()) return fail("initial_cov has a non-finite entry");
  if (!initial_state.allFinite()) return fail("initial_state has a non-finite entry");
  for (int i = 0; i < kStateSize; ++i) {
    if (process_noise(i, i) < 0.0)
      return fail(fmt::format("process_noise({0},{0}) = {1} < 0", i, process_noise(i, i)));
    if (initial_cov(i, i) < 0.0)
      return fail(fmt::format("initial_cov({0},{0}) = {1} < 0", i, initial_cov(i, i)));
  }
  return true;
}

RlEkf::RlEkf(const RlEkfParams& params)
    : Q_(params.process_noise),
      dynamic_q_(params.dynamic_process_noise),
      x_(params.initial_state),
      P_(params.initial_cov) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("RlEkfParams: " + why);
}

void RlEkf::predict(double dt_s) {
  const OffIdentity t = model_terms(x_, dt_s);
  // FilterBase::computeDynamicProcessNoiseCovariance, on the state before the
  // projection: the pose block of Q scaled by the squared norm of the twist.
  const double speed2 = dynamic_q_ ? x_.segment<6>(kVx).squaredNorm() : 1.0;

  State x_next = x_;
  for (int k = 0; k < kTransferTerms; ++k) x_next[t.terms[k].row] += t.terms[k].value * x_[t.terms[k].col];
  x_ = x_next;
  wrap_angles(x_);

  // P ← J·P·Jᵀ with J = I + D: first B = P·Jᵀ = P + P·Dᵀ, then J·B = B + D·B.
  Cov B = P_;
  for (int k = 0; k < t.size; ++k) B.col(t.terms[k].row) += t.terms[k].value * P_.col(t.terms[k].col);
  P_ = B;
  for (int k = 0; k < t.size; ++k) P_.row(t.terms[k].row) += t.terms[k].value * B.row(t.terms[k].col);

  if (dynamic_q_) {
    P_.topLeftCorner<6, 6>() += dt_s * speed2 * Q_.topLeftCorner<6, 6>();
    P_.topRightCorner<6, 9>() += dt_s * Q_.topRightCorner<6, 9>();
    P_.bottomRows<9>() += dt_s * Q_.bottomRows<9>();
  } else {
    P_ += dt_s * Q_;
  }
}

namespace {

// The correction for a measurement of N members, at fixed size so that the
// products are unrolled and vectorised; coefficient-based (lazyProduct):
// Eigen's blocked product for 15 × N × 15 costs more than it saves here.
template <int N>
bool correct_fixed(State& x, Cov& P, const Measurement& m, const std::array<int, kStateSize>& idx) {
  Eigen::Matrix<double, N, N> R, S;
  Eigen::Matrix<double, N, 1> nu;
  Eigen::Matrix<double, kStateSize, N> PHt;
  Eigen::Matrix<double, N, kStateSize> HP;
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) R(i, j) = m.R(idx[i], idx[j]);
    // A negative variance is taken by its magnitude, one below 1e-9 raised to it.
    R(i, i) = std::max(std::abs(R(i, i)), 1e-9);
    nu[i] = m.z[idx[i]] - x[idx[i]];
    if (is_angle(idx[i])) nu[i] = normalize_angle(nu[i]);
    PHt.col(i) = P.col(idx[i]);
    HP.row(i) = P.row(idx[i]);
  }
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) S(i, j) = HP(i, idx[j]) + R(i, j);
  }
  // By LU, as robot_localization's dynamic-size inverse is (not the closed
  // forms Eigen uses for fixed sizes up to 4).
  const Eigen::Matrix<double, N, N> S_inv = S.partialPivLu().inverse();
  const double threshold = m.mahalanobis_threshold * m.mahalanobis_threshold;
  if (nu.dot(S_inv * nu) >= threshold) return false;

  const Eigen::Matrix<double, kStateSize, N> K = PHt * S_inv;
  x.noalias() += K * nu;
  // Joseph form (I − K·H)·P·(I − K·H)ᵀ + K·R·Kᵀ, with H a selection and
  // G = I − K·H: G·P = P − K·(H·P), then G·P·Gᵀ + K·R·Kᵀ = G·P − (G·P·Hᵀ − K·R)·Kᵀ
  // (one 15 × N × 15 product fewer than three separate terms). The fully
  // expanded P − K·H·P − (K·H·P)ᵀ + K·S·Kᵀ is cheaper still but loses the
  // covariance on the Husky bag (non-finite within the drive).
  Cov GP = P;
  GP.noalias() -= K.lazyProduct(HP);
  Eigen::Matrix<double, kStateSize, N> W;
  for (int i = 0; i < N; ++i) W.col(i) = GP.col(idx[i]);
  W.noalias() -= K.lazyProduct(R);
  P = GP;
  P.noalias() -= W.lazyProduct(K.transpose());
  return true;
}

template <int... Ns>
bool correct_sized(int n, State& x, Cov& P, const Measurement& m, const std::array<int, kStateSize>& idx,
                   std::integer_sequence<int, Ns...>) {
  bool accepted = true;
  ((n == Ns + 1 ? (accepted = correct_fixed<Ns + 1>(x, P, m, idx), true) : false) || ...);
  return accepted;
}

}  // namespace

bool RlEkf::correct(const Measurement& m) {
  std::array<int, kStateSize> idx{};
  int n = 0;
  for (int i = 0; i < kStateSize; ++i) {
    if (m.mask[i] && std::isfinite(m.z[i])) idx[n++] = i;  // nan and inf are left out (ekf.cpp)
  }
  if (n == 0) return true;
  const bool accepted = correct_sized(n, x_, P_, m, idx, std::make_integer_sequence<int, kStateSize>{});
  if (accepted) wrap_angles(x_);
  return accepted;
}

bool RlEkf::process(const Measurement& m) {
  if (!initialized_) {
    for (int i = 0; i < kStateSize; ++i) {
      if (!m.mask[i]) continue;
      x_[i] = m.z[i];
      for (int j = 0; j < kStateSize; ++j) {
        if (m.mask[j]) P_(i, j) = m.R(i, j);
      }
    }
    initialized_ = true;
    last_time_ns_ = m.time_ns;
    return true;
  }
  const std::int64_t delta = m.time_ns - last_time_ns_;
  if (delta > 0) predict(static_cast<double>(delta) * 1e-9);
  const bool accepted = correct(m);
  if (delta >= 0) last_time_ns_ = m.time_ns;
  return accepted;
}

void RlEkf::predict_to(std::int64_t time_ns) {
  const std::int64_t delta = time_ns - last_time_ns_;
  if (delta > 0) predict(static_cast<double>(delta) * 1e-9);
  last_time_ns_ = time_ns;
}

}  // namespace odotune::filters::rl

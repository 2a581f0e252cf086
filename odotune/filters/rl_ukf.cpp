#include <odotune/filters/rl_ukf.h>

#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <fmt/format.h>

#include <odotune/core/why.h>
#include <odotune/filters/rl_filter_base.h>

namespace odotune::filters::rl {
namespace {

constexpr int kUkfN = kStateSize;

// The measured subset's vectors and matrices: dynamic sizes up to 15, held
// in place (no allocation per step).
using SubVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kUkfN, 1>;
using SubMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kUkfN, kUkfN>;
using CrossMat = Eigen::Matrix<double, kUkfN, Eigen::Dynamic, 0, kUkfN, kUkfN>;

bool is_angle_member(int member) { return member == kRoll || member == kPitch || member == kYaw; }

// The weighted mean of an angle over the points: atan2(Σ Wᵢ sin, Σ Wᵢ cos).
struct AngleMean {
  double sin_sum = 0.0, cos_sum = 0.0;
  void add(double w, double a) {
    cos_sum += w * std::cos(a);
    sin_sum += w * std::sin(a);
  }
  double value() const { return std::atan2(sin_sum, cos_sum); }
};

void wrap_state_angles(State& x) {
  for (int m : {kRoll, kPitch, kYaw}) x[m] = normalize_angle(x[m]);
}

// FilterBase::computeDynamicProcessNoiseCovariance: the pose block of Q
// scaled by the squared norm of the body velocities.
Cov process_noise(const Cov& Q, bool dynamic, const State& x) {
  if (!dynamic) return Q;
  Cov out = Q;
  const double speed2 = x.segment<6>(kVx).squaredNorm();
  out.topLeftCorner<6, 6>() *= speed2;
  return out;
}

}  // namespace

UkfWeights ukf_weights(double alpha, double kappa, double beta) {
  UkfWeights w;
  w.lambda = alpha * alpha * (kUkfN + kappa) - kUkfN;
  w.state[0] = w.lambda / (kUkfN + w.lambda);
  w.covariance[0] = w.state[0] + (1.0 - alpha * alpha + beta);
  for (int i = 1; i < kSigmaPoints; ++i) {
    w.state[i] = 1.0 / (2.0 * (kUkfN + w.lambda));
    w.covariance[i] = w.state[i];
  }
  return w;
}

bool RlUkfParams::IsValid(std::string* why) const {
  if (!filter.IsValid(why)) return false;
  if (!std::isfinite(alpha) || !(alpha > 0.0))
    return core::invalid(why, fmt::format("alpha = {}, expected > 0", alpha));
  if (!std::isfinite(kappa) || !(kUkfN + kappa > 0.0))
    return core::invalid(why, fmt::format("kappa = {}, expected > -15 (n + kappa > 0)", kappa));
  if (!std::isfinite(beta)) return core::invalid(why, fmt::format("beta = {}, expected a finite number", beta));
  return true;
}

RlUkf::RlUkf(const RlUkfParams& params)
    : Q_(detail::symmetric(params.filter.process_noise)),
      dynamic_q_(params.filter.dynamic_process_noise),
      w_(ukf_weights(params.alpha, params.kappa, params.beta)),
      x_(params.filter.initial_state),
      P_(detail::symmetric(params.filter.initial_cov)) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("RlUkfParams: " + why);
  for (State& s : sigma_) s.setZero();
}

void RlUkf::draw_sigma_points() {
  // LLᵀ = (n + λ)P; Eigen's LLT, as ukf.cpp takes it (not checked for success).
  const Cov L = (static_cast<double>(kUkfN) + w_.lambda) * P_;
  const Cov root = L.llt().matrixL();
  sigma_[0] = x_;
  for (int i = 0; i < kUkfN; ++i) {
    sigma_[1 + i] = x_ + root.col(i);
    sigma_[1 + kUkfN + i] = x_ - root.col(i);
  }
}

void RlUkf::predict(double dt_s) {
  draw_sigma_points();
  x_.setZero();
  AngleMean angle[3];
  for (int s = 0; s < kSigmaPoints; ++s) {
    sigma_[s] = advance(sigma_[s], dt_s);
    x_ += w_.state[s] * sigma_[s];
    for (int a = 0; a < 3; ++a) angle[a].add(w_.state[s], sigma_[s][kRoll + a]);
  }
  for (int a = 0; a < 3; ++a) x_[kRoll + a] = angle[a].value();
  P_.setZero();
  for (int s = 0; s < kSigmaPoints; ++s) {
    State d = sigma_[s] - x_;
    for (int a = kRoll; a <= kYaw; ++a) d[a] = normalize_angle(d[a]);
    P_ += w_.covariance[s] * (d * d.transpose());
  }
  P_ += dt_s * process_noise(Q_, dynamic_q_, x_);
  wrap_state_angles(x_);
  uncorrected_ = true;
}

bool RlUkf::correct(const Measurement& m) {
  if (!uncorrected_) draw_sigma_points();
  int idx[kUkfN];
  const int n = detail::fused_members(m, idx);
  if (n == 0) {  // ukf.cpp's update with an empty subset changes nothing but this
    wrap_state_angles(x_);
    uncorrected_ = false;
    return true;
  }
  double zr[kUkfN], Rr[kUkfN * kUkfN];
  detail::gather(m, n, idx, zr, Rr);
  const SubVec z = Eigen::Map<const SubVec>(zr, n);
  const SubMat R = Eigen::Map<const SubMat>(Rr, n, n);

  // (1) The points' predicted measurement.
  std::array<SubVec, kSigmaPoints> Z;
  SubVec z_hat = SubVec::Zero(n);
  AngleMean angle[3];
  for (int s = 0; s < kSigmaPoints; ++s) {
    Z[s].resize(n);
    for (int a = 0; a < n; ++a) Z[s][a] = sigma_[s][idx[a]];
    z_hat += w_.state[s] * Z[s];
    for (int a = 0; a < n; ++a) {
      if (is_angle_member(idx[a])) angle[idx[a] - kRoll].add(w_.state[s], Z[s][a]);
    }
  }
  for (int a = 0; a < n; ++a) {
    if (is_angle_member(idx[a])) z_hat[a] = angle[idx[a] - kRoll].value();
  }
  // (2) P_zz and P_xz.
  SubMat Pzz = SubMat::Zero(n, n);
  CrossMat Pxz = CrossMat::Zero(kUkfN, n);
  for (int s = 0; s < kSigmaPoints; ++s) {
    SubVec dz = Z[s] - z_hat;
    State dx = sigma_[s] - x_;
    for (int a = 0; a < n; ++a) {
      if (!is_angle_member(idx[a])) continue;
      dz[a] = normalize_angle(dz[a]);
      dx[a] = normalize_angle(dx[a]);  // position a, not idx[a]: as ukf.cpp does
    }
    Pzz += w_.covariance[s] * (dz * dz.transpose());
    Pxz += w_.covariance[s] * (dx * dz.transpose());
  }
  // (3)–(5) The gain, the innovation and its gate.
  const SubMat S_inv = (Pzz + R).inverse();
  const CrossMat K = Pxz * S_inv;
  SubVec nu = z - z_hat;
  for (int a = 0; a < n; ++a) {
    if (is_angle_member(idx[a])) nu[a] = normalize_angle(nu[a]);
  }
  const double thr = m.mahalanobis_threshold;
  if (nu.dot(S_inv * nu) >= thr * thr) return false;
  // (6) The update, P less K·P_zz·Kᵀ.
  x_ += K * nu;
  P_ -= K * Pzz * K.transpose();
  wrap_state_angles(x_);
  uncorrected_ = false;
  return true;
}

bool RlUkf::process(const Measurement& m) {
  return detail::process_measurement(
      initialized_, last_time_ns_, m.time_ns,
      [&] {
        detail::initialise(m, x_, P_);
        return true;
      },
      [&](double dt) { predict(dt); }, [&] { return correct(m); });
}

void RlUkf::predict_to(std::int64_t time_ns) {
  detail::predict_to(last_time_ns_, time_ns, [&](double dt) { predict(dt); });
}

}  // namespace odotune::filters::rl

#include <odotune/filters/velocity_ukf.h>

#include <odotune/core/why.h>
#include <odotune/filters/unscented.h>

#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace odotune::filters {
namespace {

constexpr int kN = 2;               // state dimension n
constexpr int kSigma = 2 * kN + 1;  // 2n + 1 sigma points

std::string describe(const char* name, double x, const char* expected) {
  std::ostringstream os;
  os << name << " = " << x << " must be " << expected;
  return os.str();
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

unscented::SigmaWeights<kN> sigma_weights(const UkfParams& p) {
  return unscented::sigma_weights<kN>(p.alpha, p.beta, p.kappa);
}

}  // namespace

bool UkfParams::IsValid(std::string* why) const {
  if (!(std::isfinite(q_v_m2_s3) && q_v_m2_s3 >= 0.0))
    return core::invalid(why, describe("q_v_m2_s3", q_v_m2_s3, "a finite number >= 0 [(m/s)^2/s]"));
  if (!(std::isfinite(q_w_rad2_s3) && q_w_rad2_s3 >= 0.0))
    return core::invalid(why, describe("q_w_rad2_s3", q_w_rad2_s3, "a finite number >= 0 [(rad/s)^2/s]"));
  if (!unscented::parameters_valid<kN>(alpha, beta, kappa, why)) return false;
  if (!initial_state.allFinite()) return core::invalid(why, "initial_state must be finite");
  if (!is_spd(initial_cov)) return core::invalid(why, "initial_cov must be symmetric positive definite");
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
  const auto w = sigma_weights(p_);
  unscented::SigmaPoints<kN> chi;
  if (!unscented::sigma_points<kN>(x_, P_, w.lambda, &chi)) {
    healthy_ = false;
    return;
  }
  // f(χ) = χ: "uniform rectilinear motion", constant (V, W) (paper §1).
  const unscented::SigmaPoints<kN> chi_pred = chi;
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

// The unscented update (odotune/filters/unscented.h) with h picking rows of the state
// (a full (V, W) measurement or W alone); false unless the result is finite
// and P positive definite.
template <int M, typename Measure>
bool unscented_update(const UkfParams& p, Velocity* x, VelocityCov* P, const Eigen::Matrix<double, M, 1>& z,
                      const Eigen::Matrix<double, M, M>& R, Measure&& h) {
  return unscented::update<kN, M>(sigma_weights(p), x, P, z, R, std::forward<Measure>(h)) && is_spd(*P);
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

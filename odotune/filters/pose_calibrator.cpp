#include <odotune/filters/pose_calibrator.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/LU>
#include <fmt/format.h>

#include <odotune/core/planar_motion.h>
#include <odotune/core/why.h>
#include <odotune/filters/diff_drive.h>

namespace odotune::filters {

namespace {

bool positive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

bool PoseCalibratorParams::IsValid(std::string* why) const {
  std::string sub;
  if (!initial.IsValid(&sub)) return core::invalid(why, "initial." + sub);
  if (!positive(initial_sd_radius_frac))
    return core::invalid(why, fmt::format("initial_sd_radius_frac = {} must be > 0", initial_sd_radius_frac));
  if (!positive(initial_sd_wheel_base_frac))
    return core::invalid(why, fmt::format("initial_sd_wheel_base_frac = {} must be > 0",
                                          initial_sd_wheel_base_frac));
  if (!(std::isfinite(wheel_noise_m2_per_m) && wheel_noise_m2_per_m >= 0.0))
    return core::invalid(why, fmt::format("wheel_noise_m2_per_m = {} must be ≥ 0", wheel_noise_m2_per_m));
  if (!positive(gate_nis)) return core::invalid(why, fmt::format("gate_nis = {} must be > 0", gate_nis));
  if (max_rejected_fixes < 1)
    return core::invalid(why, fmt::format("max_rejected_fixes = {} must be ≥ 1", max_rejected_fixes));
  if (!positive(acquire_spread_sigmas))
    return core::invalid(why, fmt::format("acquire_spread_sigmas = {} must be > 0", acquire_spread_sigmas));
  if (acquire_min_fixes < 2)
    return core::invalid(why, fmt::format("acquire_min_fixes = {} must be ≥ 2", acquire_min_fixes));
  if (!memory.IsValid(&sub)) return core::invalid(why, "memory." + sub);
  return true;
}

PcPrediction pose_calibrator_predict(const PcState& s, double dphi_left_rad, double dphi_right_rad) {
  const double l = s(kPcRadiusLeft) * dphi_left_rad;
  const double r = s(kPcRadiusRight) * dphi_right_rad;
  const double base = s(kPcWheelBase);
  const MotionStep step = diff_drive_step(Pose(s(kPcX), s(kPcY), s(kPcTheta)), {l, r}, base);
  PcPrediction out;
  out.next = s;
  out.next.head<3>() = step.next;
  out.F.setIdentity();
  out.F.topLeftCorner<3, 3>() = step.F;
  out.F.block<3, 1>(0, kPcRadiusLeft) = step.V.col(kLeft) * dphi_left_rad;
  out.F.block<3, 1>(0, kPcRadiusRight) = step.V.col(kRight) * dphi_right_rad;
  // Δθ = (r − l)/D and θm = θ + Δθ/2, so ∂Δθ/∂D = −Δθ/D, ∂θm/∂D = −Δθ/(2D);
  // ∂x'/∂θm and ∂y'/∂θm are F's heading column.
  const double dtheta = (r - l) / base;
  const double dthm_dd = -0.5 * dtheta / base;
  out.F(kPcX, kPcWheelBase) = step.F(kX, kTheta) * dthm_dd;
  out.F(kPcY, kPcWheelBase) = step.F(kY, kTheta) * dthm_dd;
  out.F(kPcTheta, kPcWheelBase) = -dtheta / base;
  out.G.setZero();
  out.G.topRows<3>() = step.V;
  return out;
}

bool DistanceMemoryParams::IsValid(std::string* why) const {
  if (!(positive(min_memory_m) && positive(max_memory_m) && min_memory_m <= max_memory_m))
    return core::invalid(why, fmt::format("memory {}–{} m: expected 0 < min_memory_m ≤ max_memory_m",
                                          min_memory_m, max_memory_m));
  return true;
}

PoseCalibrator::PoseCalibrator(const PoseCalibratorParams& params)
    : params_(params), memory_(distance_memory(params.memory)) {
  std::string why;
  if (!params_.IsValid(&why)) throw std::invalid_argument("pose calibrator: " + why);
  const OdometryParams& g = params_.initial;
  x_.setZero();
  x_(kPcRadiusLeft) = g.wheel_radius_left_m;
  x_(kPcRadiusRight) = g.wheel_radius_right_m;
  x_(kPcWheelBase) = g.wheel_base_m;
  const double sl = params_.initial_sd_radius_frac * g.wheel_radius_left_m;
  const double sr = params_.initial_sd_radius_frac * g.wheel_radius_right_m;
  const double sd = params_.initial_sd_wheel_base_frac * g.wheel_base_m;
  geometry_var0_ = Eigen::Vector3d(sl * sl, sr * sr, sd * sd);
  P_.setZero();
  P_.bottomRightCorner<3, 3>() = geometry_var0_.asDiagonal();
  estimate_.params = g;
  estimate_.sd_radius_left_m = sl;
  estimate_.sd_radius_right_m = sr;
  estimate_.sd_wheel_base_m = sd;
  start_from_fixes();
}

void PoseCalibrator::start_at(const PlanarPose& pose, double sd_xy_m, double sd_theta_rad) {
  if (!(std::isfinite(pose.x_m) && std::isfinite(pose.y_m) && std::isfinite(pose.theta_rad) &&
        std::isfinite(sd_xy_m) && sd_xy_m >= 0.0 && std::isfinite(sd_theta_rad) && sd_theta_rad >= 0.0))
    throw std::invalid_argument("pose calibrator: a known start needs a finite pose and sds ≥ 0");
  x_(kPcX) = pose.x_m;
  x_(kPcY) = pose.y_m;
  x_(kPcTheta) = pose.theta_rad;
  P_.topRows<3>().setZero();
  P_.leftCols<3>().setZero();
  P_(kPcX, kPcX) = P_(kPcY, kPcY) = sd_xy_m * sd_xy_m;
  P_(kPcTheta, kPcTheta) = sd_theta_rad * sd_theta_rad;
  pose_known_ = true;
  acq_ = Acquisition{};
  rejected_in_row_ = 0;
}

void PoseCalibrator::start_from_fixes() {
  pose_known_ = false;
  acq_ = Acquisition{};
  rejected_in_row_ = 0;
}

const CalibEstimate& PoseCalibrator::step(const PoseCalibSample& s) {
  const bool fix_ok = !s.has_fix || (std::isfinite(s.fix_x_m) && std::isfinite(s.fix_y_m) &&
                                     positive(s.fix_var_x_m2) && positive(s.fix_var_y_m2));
  if (!(std::isfinite(s.dt_s) && s.dt_s >= 0.0 && std::isfinite(s.dphi_left_rad) &&
        std::isfinite(s.dphi_right_rad) && fix_ok))
    throw std::invalid_argument(fmt::format(
        "pose calibrator: bad sample (dt {} s, wheel angles {} / {} rad, fix {} {} var {} {})", s.dt_s,
        s.dphi_left_rad, s.dphi_right_rad, s.fix_x_m, s.fix_y_m, s.fix_var_x_m2, s.fix_var_y_m2));
  last_log_predictive_ = 0.0;
  if (pose_known_) {
    predict(s);
    if (s.has_fix) fix_update(s);
  } else {
    acquire(s);
  }
  ++iteration_;
  refresh_estimate(s);
  return estimate_;
}

void PoseCalibrator::predict(const PoseCalibSample& s) {
  const PcPrediction p = pose_calibrator_predict(x_, s.dphi_left_rad, s.dphi_right_rad);
  const double l = std::abs(x_(kPcRadiusLeft) * s.dphi_left_rad);
  const double r = std::abs(x_(kPcRadiusRight) * s.dphi_right_rad);
  const Eigen::Vector2d q(params_.wheel_noise_m2_per_m * l, params_.wheel_noise_m2_per_m * r);
  rolled_since_fix_m_ += 0.5 * (l + r);
  x_ = p.next;
  P_ = p.F * P_ * p.F.transpose() + p.G * q.asDiagonal() * p.G.transpose();
}

void PoseCalibrator::fade(double rolled_m) {
  const double inflate = memory_.step(rolled_m);
  const double s = std::sqrt(1.0 + inflate);
  P_.bottomRows<3>() *= s;
  P_.rightCols<3>() *= s;
  // Bounded: no geometry variance past its initial one (a direction the
  // drive does not excite cannot wind up).
  for (int k = 0; k < 3; ++k) {
    const int i = kPcRadiusLeft + k;
    if (P_(i, i) > geometry_var0_(k)) {
      const double f = std::sqrt(geometry_var0_(k) / P_(i, i));
      P_.row(i) *= f;
      P_.col(i) *= f;
    }
  }
}

void PoseCalibrator::fix_update(const PoseCalibSample& s) {
  fade(rolled_since_fix_m_);
  rolled_since_fix_m_ = 0.0;
  const Eigen::Vector2d z(s.fix_x_m, s.fix_y_m);
  const Eigen::Matrix2d R = Eigen::Vector2d(s.fix_var_x_m2, s.fix_var_y_m2).asDiagonal();
  const Eigen::Vector2d nu = z - x_.head<2>();
  Eigen::Matrix2d S = P_.topLeftCorner<2, 2>() + R;
  Eigen::Matrix2d S_inv = S.inverse();
  const double nis = nu.dot(S_inv * nu);
  last_log_predictive_ = -0.5 * nis - 0.5 * std::log(S.determinant()) - std::log(2.0 * std::numbers::pi);
  if (nis > params_.gate_nis) {
    if (++rejected_in_row_ < params_.max_rejected_fixes) {
      ++fixes_rejected_;
      return;
    }
    // The pose is lost (the fixes jumped, the robot was carried): widen its
    // covariance to hold this fix, and apply it.
    P_(kPcX, kPcX) += nu.x() * nu.x();
    P_(kPcY, kPcY) += nu.y() * nu.y();
    P_(kPcTheta, kPcTheta) += 0.25;  // (0.5 rad)²
    S = P_.topLeftCorner<2, 2>() + R;
    S_inv = S.inverse();
    ++reacquisitions_;
  }
  rejected_in_row_ = 0;
  const Eigen::Matrix<double, kPcDim, 2> K = P_.leftCols<2>() * S_inv;
  const PcState next = x_ + K * nu;
  if (!(next(kPcRadiusLeft) > 0.0 && next(kPcRadiusRight) > 0.0 && next(kPcWheelBase) > 0.0)) return;
  x_ = next;
  PcCov ikh = PcCov::Identity();
  ikh.leftCols<2>() -= K;
  P_ = ikh * P_ * ikh.transpose() + K * R * K.transpose();
  P_ = (0.5 * (P_ + P_.transpose())).eval();
  ++fixes_applied_;
}

void PoseCalibrator::acquire(const PoseCalibSample& s) {
  // Fixes that have not spread in this many samples place nothing (a robot
  // standing still): the acquisition starts over from here.
  if (acq_.samples.size() >= kMaxReplaySamples) acq_ = Acquisition{};
  acq_.samples.push_back(s);
  PlanarPose& o = acq_.odometry;
  const PlanarPose before = o;
  core::midpoint_advance(&o.x_m, &o.y_m, &o.theta_rad, x_(kPcRadiusLeft) * s.dphi_left_rad,
                         x_(kPcRadiusRight) * s.dphi_right_rad, x_(kPcWheelBase));
  acq_.turn_rad += std::abs(o.theta_rad - before.theta_rad);
  acq_.distance_m += std::hypot(o.x_m - before.x_m, o.y_m - before.y_m);
  if (!s.has_fix) return;
  rolled_since_fix_m_ = 0.0;
  const Eigen::Vector2d q(s.fix_x_m, s.fix_y_m);
  acq_.odo.emplace_back(o.x_m, o.y_m);
  acq_.fix.push_back(q);
  acq_.var_sum += 0.5 * (s.fix_var_x_m2 + s.fix_var_y_m2);
  const auto n = static_cast<double>(acq_.fix.size());
  // The fixes' spread Σ|q − q̄|², kept as it grows (Welford) so that waiting
  // for it costs O(1) per fix; the rigid fit runs once, when it suffices.
  const Eigen::Vector2d delta = q - acq_.fix_mean;
  acq_.fix_mean += delta / n;
  acq_.fix_spread_m2 += delta.dot(q - acq_.fix_mean);
  const double var = acq_.var_sum / n;
  const double k = params_.acquire_spread_sigmas;
  if (static_cast<int>(acq_.fix.size()) < params_.acquire_min_fixes || acq_.fix_spread_m2 / n < k * k * var)
    return;
  const core::RigidMotion2d fit = core::fit_rigid_2d(
      acq_.fix.size(), [&](std::size_t i) { return acq_.odo[i].x(); },
      [&](std::size_t i) { return acq_.odo[i].y(); }, [&](std::size_t i) { return acq_.fix[i].x(); },
      [&](std::size_t i) { return acq_.fix[i].y(); });
  // The pose where the acquisition began: the origin of the filter's own frame.
  PlanarPose start{0.0, 0.0, 0.0};
  fit.apply(&start.x_m, &start.y_m, &start.theta_rad);
  // The heading's sd: the fit's own (σ²/Σ|q − q̄|²), plus what the initial
  // geometry's uncertainty does to the dead reckoning over the acquisition
  // (a wheel-base error scales the turns, a radius difference bends the
  // path); the position's likewise with the radii's scale.
  const double sd_base = params_.initial_sd_wheel_base_frac, sd_radius = params_.initial_sd_radius_frac;
  const double sd_theta = std::sqrt(var / fit.spread_m2) + acq_.turn_rad * sd_base +
                          acq_.distance_m * std::sqrt(2.0) * sd_radius / x_(kPcWheelBase);
  const double sd_xy = std::sqrt(var) + acq_.distance_m * sd_radius;
  replay_from(start, sd_xy, sd_theta);
}

void PoseCalibrator::replay_from(const PlanarPose& start, double sd_xy_m, double sd_theta_rad) {
  // The acquisition's fixes placed the pose; replaying its samples from
  // there lets them inform the geometry too (on short runs they are a good
  // share of all the fixes).
  const std::vector<PoseCalibSample> samples = std::move(acq_.samples);
  start_at(start, sd_xy_m, sd_theta_rad);
  rolled_since_fix_m_ = 0.0;
  for (const PoseCalibSample& s : samples) {
    predict(s);
    if (s.has_fix) fix_update(s);
  }
  // The change test compares the twins fix by fix from here on.
  last_log_predictive_ = 0.0;
}

void PoseCalibrator::refresh_estimate(const PoseCalibSample& s) {
  estimate_.params = {x_(kPcRadiusLeft), x_(kPcRadiusRight), x_(kPcWheelBase)};
  estimate_.sd_radius_left_m = std::sqrt(P_(kPcRadiusLeft, kPcRadiusLeft));
  estimate_.sd_radius_right_m = std::sqrt(P_(kPcRadiusRight, kPcRadiusRight));
  estimate_.sd_wheel_base_m = std::sqrt(P_(kPcWheelBase, kPcWheelBase));
  if (s.dt_s > 0.0)
    estimate_.velocity = body_velocity(estimate_.params, s.dphi_left_rad / s.dt_s, s.dphi_right_rad / s.dt_s);
}

}  // namespace odotune::filters

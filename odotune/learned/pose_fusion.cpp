#include <odotune/learned/pose_fusion.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/why.h>

namespace odotune::learned {
namespace {

[[noreturn]] void fail_pose_fusion(const FusionInput& in, const std::string& what) {
  throw std::invalid_argument(fmt::format("track '{}': {}", in.track_name, what));
}

// The filter's start (the header's rule).
void start_state(const FusionInput& in, const PoseFusionOptions& o, filters::PoseUkfParams* p) {
  p->initial_state.setZero();
  p->initial_cov = filters::PoseVelocityCov::Identity() * 1e-2;
  const double sm2 = o.start_sigma_m * o.start_sigma_m;
  if (std::isfinite(in.gt_x[0]) && std::isfinite(in.gt_y[0]) && std::isfinite(in.gt_theta[0])) {
    p->initial_state.head<3>() << in.gt_x[0], in.gt_y[0], in.gt_theta[0];
    p->initial_cov(filters::kPx, filters::kPx) = p->initial_cov(filters::kPy, filters::kPy) = sm2;
    p->initial_cov(filters::kPtheta, filters::kPtheta) = o.start_sigma_rad * o.start_sigma_rad;
    return;
  }
  for (std::size_t k = 0; k < in.size(); ++k)
    if (std::isfinite(in.fix_x[k])) {
      p->initial_state.head<2>() << in.fix_x[k], in.fix_y[k];
      break;
    }
  p->initial_cov(filters::kPtheta, filters::kPtheta) = std::numbers::pi * std::numbers::pi;
}

void record_pose(const filters::PoseVelocityUkf& f, std::size_t k, PoseFusionTrace& t) {
  const filters::PoseVelocity& s = f.state();
  t.x[k] = s(filters::kPx);
  t.y[k] = s(filters::kPy);
  t.theta[k] = s(filters::kPtheta);
  t.v[k] = s(filters::kPv);
  t.w[k] = s(filters::kPw);
}

}  // namespace

bool PoseFusionOptions::IsValid(std::string* why) const {
  if (!(std::isfinite(fix_sigma_m) && fix_sigma_m >= 0.0))
    return core::invalid(why, fmt::format("fix_sigma_m = {}: expected a finite value >= 0 [m]", fix_sigma_m));
  if (!(start_sigma_m > 0.0 && std::isfinite(start_sigma_m)) ||
      !(start_sigma_rad > 0.0 && std::isfinite(start_sigma_rad)))
    return core::invalid(why, "start_sigma_m, start_sigma_rad: expected finite values > 0");
  std::string inner;
  if (!ukf.IsValid(&inner)) return core::invalid(why, "ukf: " + inner);
  if (!noise.IsValid(&inner)) return core::invalid(why, "noise: " + inner);
  return true;
}

PoseFusionTrace replay_pose_fusion(const FusionInput& in, const std::vector<OdometryMeasurement>& odo,
                                   const PoseFusionOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) fail_pose_fusion(in, "pose fusion options: " + why);
  if (odo.size() != in.size())
    fail_pose_fusion(in, fmt::format("{} odometry measurements for {} steps", odo.size(), in.size()));
  if (!in.has_fixes) fail_pose_fusion(in, "no position fixes (aps_x, aps_y) to fuse");
  const double default_var = options.fix_sigma_m * options.fix_sigma_m;
  for (std::size_t k = 0; k < in.size(); ++k)
    if (std::isfinite(in.fix_x[k]) && !(in.fix_var_x[k] > 0.0 && in.fix_var_y[k] > 0.0) && !(default_var > 0.0))
      fail_pose_fusion(
          in, fmt::format("the fix at {} s has no variances (aps_var_x, aps_var_y): expected them, or a fix σ "
                          "(--fix-sigma-m)",
                          in.t[k]));
  filters::PoseUkfParams p = options.ukf;
  start_state(in, options, &p);
  filters::PoseVelocityUkf f(p);
  PoseFusionTrace t;
  const std::size_t n = in.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (auto* v : {&t.x, &t.y, &t.theta, &t.v, &t.w}) v->assign(n, nan);
  if (n > 0) record_pose(f, 0, t);
  for (std::size_t k = 1; k < n && f.healthy(); ++k) {
    f.predict(in.dt_s);
    f.update_velocity(odo[k].v_m_s, odo[k].w_rad_s, Eigen::Vector2d(odo[k].var_v, odo[k].var_w).asDiagonal());
    if (options.noise.use_gyro && std::isfinite(in.gyro_z[k]))
      f.update_yaw_rate(in.gyro_z[k], options.noise.gyro_var);
    if (options.noise.use_external && std::isfinite(in.v_ext[k]))
      f.update_velocity(in.v_ext[k], in.w_ext[k],
                        Eigen::Vector2d(in.v_ext_var[k], in.w_ext_var[k]).asDiagonal() *
                            options.noise.ext_var_scale);
    if (std::isfinite(in.fix_x[k])) {
      const bool own = in.fix_var_x[k] > 0.0 && in.fix_var_y[k] > 0.0;
      f.update_position(in.fix_x[k], in.fix_y[k],
                        Eigen::Vector2d(own ? in.fix_var_x[k] : default_var,
                                        own ? in.fix_var_y[k] : default_var)
                            .asDiagonal());
      ++t.fixes;
    }
    if (f.healthy()) record_pose(f, k, t);
  }
  t.healthy = f.healthy();
  return t;
}

objectives::ErrorMetrics pose_fusion_errors(const FusionInput& in, const PoseFusionTrace& trace) {
  return position_errors(in, trace.x, trace.y);
}

}  // namespace odotune::learned

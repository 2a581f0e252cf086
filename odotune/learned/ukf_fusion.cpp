#include <odotune/learned/ukf_fusion.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/why.h>

namespace odotune::learned {

bool UkfSensorNoise::IsValid(std::string* why) const {
  if (!(std::isfinite(gyro_var) && gyro_var > 0.0))
    return core::invalid(why, fmt::format("gyro_var = {} must be a finite number > 0 [(rad/s)^2]", gyro_var));
  if (!(std::isfinite(ext_var_scale) && ext_var_scale > 0.0))
    return core::invalid(why, fmt::format("ext_var_scale = {} must be a finite number > 0", ext_var_scale));
  return true;
}

std::vector<OdometryMeasurement> static_odometry(const FusionInput& in, double var_v, double var_w) {
  if (!(std::isfinite(var_v) && var_v > 0.0))
    throw std::invalid_argument(fmt::format("odometry var_v = {} must be a finite number > 0 [(m/s)^2]",
                                            var_v));
  if (!(std::isfinite(var_w) && var_w > 0.0))
    throw std::invalid_argument(fmt::format("odometry var_w = {} must be a finite number > 0 [(rad/s)^2]",
                                            var_w));
  std::vector<OdometryMeasurement> out(in.size());
  for (std::size_t k = 0; k < in.size(); ++k) out[k] = {in.v_kin[k], in.w_kin[k], var_v, var_w};
  return out;
}

void fuse_step(filters::VelocityUkf& ukf, const FusionInput& in, std::size_t k, const OdometryMeasurement& odo,
               const UkfSensorNoise& noise) {
  using filters::kV;
  using filters::kW;
  ukf.predict(in.dt_s);
  ukf.update(filters::Velocity(odo.v_m_s, odo.w_rad_s),
             filters::Velocity(odo.var_v, odo.var_w).asDiagonal().toDenseMatrix());
  if (noise.use_external && in.has_ext && !std::isnan(in.v_ext[k]) && !std::isnan(in.w_ext[k])) {
    const filters::VelocityCov R =
        filters::Velocity(in.v_ext_var[k], in.w_ext_var[k]).asDiagonal().toDenseMatrix() * noise.ext_var_scale;
    ukf.update(filters::Velocity(in.v_ext[k], in.w_ext[k]), R);
  }
  if (noise.use_gyro && in.has_gyro && !std::isnan(in.gyro_z[k]))
    ukf.update_yaw_rate(in.gyro_z[k], noise.gyro_var);
}

FusionTrace replay_fusion(const FusionInput& in, const std::vector<OdometryMeasurement>& odo,
                          const filters::UkfParams& params, const UkfSensorNoise& noise) {
  using filters::kV;
  using filters::kW;
  if (odo.size() != in.size())
    throw std::invalid_argument(fmt::format("track '{}': {} odometry measurements for {} fusion steps",
                                            in.track_name, odo.size(), in.size()));
  std::string why;
  if (!noise.IsValid(&why)) throw std::invalid_argument("UkfSensorNoise: " + why);
  filters::VelocityUkf ukf(params);  // throws with UkfParams' message

  const std::size_t n = in.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  FusionTrace tr;
  for (auto* v : {&tr.v, &tr.w, &tr.var_v, &tr.var_w, &tr.cov_vw, &tr.x, &tr.y, &tr.theta}) v->assign(n, nan);
  if (n == 0) return tr;

  filters::PlanarPose pose;
  if (in.has_gt && std::isfinite(in.gt_x[0]) && std::isfinite(in.gt_y[0]) && std::isfinite(in.gt_theta[0]))
    pose = {in.gt_x[0], in.gt_y[0], in.gt_theta[0]};
  auto record = [&](std::size_t k) {
    const filters::Velocity& x = ukf.state();
    const filters::VelocityCov& P = ukf.cov();
    tr.v[k] = x(kV);
    tr.w[k] = x(kW);
    tr.var_v[k] = P(kV, kV);
    tr.var_w[k] = P(kW, kW);
    tr.cov_vw[k] = P(kV, kW);
    tr.x[k] = pose.x_m;
    tr.y[k] = pose.y_m;
    tr.theta[k] = pose.theta_rad;
  };
  record(0);
  for (std::size_t k = 1; k < n; ++k) {
    fuse_step(ukf, in, k, odo[k], noise);
    if (!ukf.healthy()) {
      tr.healthy = false;
      break;  // the rest stays NaN
    }
    // Eq. 3 with the filtered velocities of step k (its interval (t[k−1], t[k]]).
    pose = filters::integrate_pose(pose, ukf.state()(kV), ukf.state()(kW), in.dt_s);
    record(k);
  }
  return tr;
}

objectives::ErrorMetrics position_errors(const FusionInput& in, const std::vector<double>& x,
                                         const std::vector<double>& y) {
  objectives::ErrorAccumulator acc;
  const std::size_t n = std::min({in.size(), x.size(), y.size()});
  for (std::size_t k = 1; k < n; ++k) {
    if (std::isnan(in.gt_x[k]) || std::isnan(in.gt_y[k])) continue;
    acc.add(std::hypot(x[k] - in.gt_x[k], y[k] - in.gt_y[k]));
  }
  return acc.metrics();
}

objectives::ErrorMetrics fusion_pose_errors(const FusionInput& in, const FusionTrace& trace) {
  return position_errors(in, trace.x, trace.y);
}

}  // namespace odotune::learned

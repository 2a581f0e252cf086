#include <odotune/diagnose/gyro_heading_input.h>

#include <algorithm>
#include <vector>

#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/series_interp.h>

namespace odotune::diagnose {

DiagInput gyro_heading_input(const DiagInput& in, double bias_radps, double scale) {
  DiagInput g = in;
  const std::vector<double>& t = in.odo_t_s;
  std::vector<double> s(t.size(), 0.0);
  if (in.odometry == OdometryKind::wheel_angles) {
    for (std::size_t i = 0; i < t.size(); ++i)
      s[i] = 0.5 * (in.radius_l_m * in.phi_l_rad[i] + in.radius_r_m * in.phi_r_rad[i]);
  }
  g.odometry = OdometryKind::body_velocity;
  g.v_mps.assign(t.size(), 0.0);
  g.w_radps.assign(t.size(), 0.0);
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (in.odometry == OdometryKind::wheel_angles) {
      const std::size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, t.size() - 1);
      g.v_mps[i] = t[b] > t[a] ? (s[b] - s[a]) / (t[b] - t[a]) : 0.0;
    } else {
      g.v_mps[i] = in.v_mps[i];
    }
    const double gz = interp_held(in.gyro_t_s, in.gyro_z_radps, t[i]);  // held outside
    g.w_radps[i] = corrected_gyro_rate(gz, bias_radps, scale);
  }
  g.cmd_v_mps.clear();
  g.cmd_w_radps.clear();
  return g;
}

}  // namespace odotune::diagnose

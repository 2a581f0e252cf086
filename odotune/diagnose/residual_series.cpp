#include <odotune/diagnose/residual_series.h>

#include <odotune/core/angles.h>
#include <odotune/diagnose/series_interp.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace odotune::diagnose {
namespace {

// Central difference of y over [tq − h, tq + h] clipped to t's span.
double rate(const std::vector<double>& t, const std::vector<double>& y, double tq, double h) {
  const double a = std::max(t.front(), tq - h), b = std::min(t.back(), tq + h);
  if (b - a <= 0.0) return 0.0;
  return (interp_held(t, y, b) - interp_held(t, y, a)) / (b - a);
}

}  // namespace

NominalKinematics nominal_kinematics(const DiagInput& in, const std::vector<double>& t_s,
                                     const ResidualSeriesOptions& o) {
  const std::vector<double>& t = in.odo_t_s;
  NominalKinematics k;
  if (t.size() < 2) {
    k.v_mps.assign(t_s.size(), 0.0), k.w_radps.assign(t_s.size(), 0.0), k.accel_mps2.assign(t_s.size(), 0.0);
    return k;
  }
  std::vector<double> s(t.size(), 0.0), h(t.size(), 0.0);
  if (in.odometry == OdometryKind::wheel_angles) {
    const double base = in.wheel_base_m > 0.0 ? in.wheel_base_m : 1.0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      const double l = in.radius_l_m * in.phi_l_rad[i], r = in.radius_r_m * in.phi_r_rad[i];
      s[i] = 0.5 * (l + r);
      h[i] = (r - l) / base;
    }
  } else {
    for (std::size_t i = 1; i < t.size(); ++i) {
      const double dt = t[i] - t[i - 1];
      s[i] = s[i - 1] + 0.5 * (in.v_mps[i] + in.v_mps[i - 1]) * dt;
      h[i] = h[i - 1] + 0.5 * (in.w_radps[i] + in.w_radps[i - 1]) * dt;
    }
  }
  k.v_mps.resize(t_s.size());
  k.w_radps.resize(t_s.size());
  k.accel_mps2.resize(t_s.size());
  for (std::size_t i = 0; i < t_s.size(); ++i) {
    k.v_mps[i] = rate(t, s, t_s[i], o.rate_half_s);
    k.w_radps[i] = rate(t, h, t_s[i], o.rate_half_s);
    const double a = std::max(t.front(), t_s[i] - o.accel_half_s);
    const double b = std::min(t.back(), t_s[i] + o.accel_half_s);
    k.accel_mps2[i] = b > a ? (rate(t, s, b, o.rate_half_s) - rate(t, s, a, o.rate_half_s)) / (b - a) : 0.0;
  }
  return k;
}

ResidualSeries residual_series(const DiagInput& in, const std::vector<Window>& windows, const ReplayResult& r,
                               const ResidualSeriesOptions& o) {
  const std::size_t n = in.ref_t_s.size();
  if (r.pred_x_m.size() != n || r.pred_y_m.size() != n)
    throw std::invalid_argument("residual_series: the replay holds " + std::to_string(r.pred_x_m.size()) +
                                " predictions for " + std::to_string(n) + " reference samples");
  const bool heading = in.has_ref_heading() && r.pred_theta_rad.size() == n;
  ResidualSeries s;
  for (const Window& w : windows) {
    for (std::size_t i = w.ref_begin; i < w.ref_end && i < n; ++i) {
      if (!std::isfinite(r.pred_x_m[i]) || !std::isfinite(r.pred_y_m[i])) continue;
      s.t_s.push_back(in.ref_t_s[i]);
      s.ex_m.push_back(r.pred_x_m[i] - in.ref_x_m[i]);
      s.ey_m.push_back(r.pred_y_m[i] - in.ref_y_m[i]);
      if (heading) s.e_theta_rad.push_back(core::wrap_angle(r.pred_theta_rad[i] - in.ref_theta_rad[i]));
      s.window.push_back(w.index);
      s.x_m.push_back(in.ref_x_m[i]);
      s.y_m.push_back(in.ref_y_m[i]);
      s.t_since_start_s.push_back(in.ref_t_s[i] - in.ref_t_s.front());
    }
  }
  const NominalKinematics k = nominal_kinematics(in, s.t_s, o);
  s.v_mps = k.v_mps;
  s.w_radps = k.w_radps;
  s.accel_mps2 = k.accel_mps2;
  return s;
}

}  // namespace odotune::diagnose

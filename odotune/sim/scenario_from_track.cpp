#include <odotune/sim/scenario_from_track.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <tuple>
#include <utility>

#include <Eigen/Dense>
#include <fmt/format.h>

#include <odotune/core/robust_stats.h>
#include <odotune/core/why.h>
#include <odotune/sim/effects.h>
#include <odotune/sim/simulator.h>

namespace odotune::sim {

namespace {

constexpr double kPi = std::numbers::pi;

// To [−π, π) by floor, not odotune/core/angles.h wrap_angle: the two can differ in the
// last bit after a wrap, and re-driven scenarios must stay as they were written.
double wrap_pi(double a) { return a - 2.0 * kPi * std::floor((a + kPi) / (2.0 * kPi)); }

// The reference samples (rows where every used column has a sample).
struct Reference {
  std::vector<double> t, x, y, th;  // th unwrapped; empty without gt_theta
  const char* what = "";            // "ground truth" / "position fixes"
  bool fixes = false;               // position fixes (noisy, sparse) rather than ground truth
};

Reference reference_of(const tracks::Track& track) {
  Reference ref;
  const bool gt = track.has_gt();
  if (!gt && !track.has_aps())
    throw std::invalid_argument(fmt::format(
        "track '{}': no reference path (neither gt_x/gt_y nor aps_x/aps_y columns); expected a track "
        "with ground truth or position fixes",
        track.name()));
  const tracks::Col cx = gt ? tracks::Col::gt_x : tracks::Col::aps_x,
                    cy = gt ? tracks::Col::gt_y : tracks::Col::aps_y;
  ref.what = gt ? "ground truth" : "position fixes";
  ref.fixes = !gt;
  auto collect = [&](bool with_theta) {
    ref.t.clear(), ref.x.clear(), ref.y.clear(), ref.th.clear();
    double prev_raw = 0.0;
    for (std::size_t i = 0; i < track.size(); ++i) {
      if (!track.at(cx, i) || !track.at(cy, i)) continue;
      if (with_theta && !track.at(tracks::Col::gt_theta, i)) continue;
      ref.t.push_back(track.t()[i]);
      ref.x.push_back(track.col(cx)[i]);
      ref.y.push_back(track.col(cy)[i]);
      if (with_theta) {
        const double raw = track.col(tracks::Col::gt_theta)[i];
        ref.th.push_back(ref.th.empty() ? raw : ref.th.back() + wrap_pi(raw - prev_raw));
        prev_raw = raw;
      }
    }
  };
  collect(gt && track.has(tracks::Col::gt_theta));
  if (!ref.th.empty() && ref.t.size() < 3) collect(false);
  if (ref.t.size() < 3)
    throw std::invalid_argument(fmt::format("track '{}': {} reference samples ({}); expected at least 3",
                                            track.name(), ref.t.size(), ref.what));
  return ref;
}

// Indices [lo, hi) of the samples used for the fit at tc (file comment of the
// header: +-h, widened nearest-first to at least min_pts samples).
std::pair<std::size_t, std::size_t> window_at(const std::vector<double>& t, double tc, double h,
                                              std::size_t min_pts) {
  std::size_t lo = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), tc - h) - t.begin());
  std::size_t hi = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), tc + h) - t.begin());
  if (hi < lo) hi = lo;
  while (hi - lo < min_pts && (lo > 0 || hi < t.size())) {
    const double left = lo > 0 ? tc - t[lo - 1] : std::numeric_limits<double>::infinity();
    const double right = hi < t.size() ? t[hi] - tc : std::numeric_limits<double>::infinity();
    if (left <= right)
      --lo;
    else
      ++hi;
  }
  return {lo, hi};
}

// Value and time derivative at tc of one coordinate.
struct Local {
  double f = 0, d1 = 0;
  double se1 = 0;  // standard error of d1 from the fit residuals (0 without spare samples)
};

// Local least-squares polynomial of each of `series` over samples [lo, hi),
// in u = (t - tc)/s: cubic with >= 4 samples, else of degree n - 1.
std::vector<Local> fit_at(const std::vector<double>& t, const std::vector<const std::vector<double>*>& series,
                          std::size_t lo, std::size_t hi, double tc) {
  const auto m = static_cast<Eigen::Index>(std::min<std::size_t>(4, hi - lo));  // coefficients
  double s = 0.0;
  for (std::size_t i = lo; i < hi; ++i) s = std::max(s, std::abs(t[i] - tc));
  if (!(s > 0.0)) s = 1.0;
  const auto ns = static_cast<Eigen::Index>(series.size());
  Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
  Eigen::Matrix<double, 4, Eigen::Dynamic> rhs = Eigen::MatrixXd::Zero(4, ns);
  for (std::size_t i = lo; i < hi; ++i) {
    const double u = (t[i] - tc) / s;
    const Eigen::Vector4d p(1.0, u, u * u, u * u * u);
    a.noalias() += p * p.transpose();
    for (Eigen::Index j = 0; j < ns; ++j) {
      const auto& f = *series[static_cast<std::size_t>(j)];
      rhs.col(j) += p * (f[i] - f[lo]);  // relative to f[lo]: no cancellation far from the origin
    }
  }
  std::vector<Local> out(series.size());
  if (m == 0) return out;
  const Eigen::MatrixXd coef = a.topLeftCorner(m, m).ldlt().solve(rhs.topRows(m));
  const auto n = static_cast<Eigen::Index>(hi - lo);
  const double inv11 = m >= 2 ? a.topLeftCorner(m, m).inverse()(1, 1) : 0.0;
  for (Eigen::Index j = 0; j < ns; ++j) {
    const auto& f = *series[static_cast<std::size_t>(j)];
    Local& o = out[static_cast<std::size_t>(j)];
    o.f = coef(0, j) + f[lo];
    o.d1 = m >= 2 ? coef(1, j) / s : 0.0;
    if (n > m && m >= 2) {
      double rss = 0.0;
      for (std::size_t i = lo; i < hi; ++i) {
        const double u = (t[i] - tc) / s;
        double p = 0.0;
        for (Eigen::Index c = m - 1; c >= 0; --c) p = p * u + coef(c, j);
        rss += (f[i] - f[lo] - p) * (f[i] - f[lo] - p);
      }
      o.se1 = std::sqrt(rss / static_cast<double>(n - m) * inv11) / s;
    }
  }
  return out;
}

// Smoothed reference motion at the knot times.
struct Motion {
  std::vector<double> t;         // knot times, shifted to start at 0 [s]
  std::vector<double> x, y, th;  // pose [m, m, rad] (th unwrapped)
  std::vector<double> v, w;      // body velocities [m/s, rad/s]
  double start_th = 0;           // heading of the scenario's start pose [rad] (header: Frames)
};

// Without gt_theta: the initial heading th0 that agrees best with the trusted
// path directions given the turning the knots command, i.e. th0 + H_k ~ th_k
// with H_k the trapezoid integral of w up to knot k (what the simulator turns
// between knots): the circular mean of th_k - H_k over the trusted knots,
// weighted by their speed (the direction of a faster fit is surer), unwrapped
// next to th_0. Unlike th_0 alone it is not thrown off by one spurious
// trusted heading while the robot stands, nor by a turn lost in an untrusted
// stretch (it then splits the loss, like a rigid best fit).
double consensus_start_heading(const Motion& m, const std::vector<bool>& known,
                               const std::vector<double>& speed) {
  double sum_s = 0.0, sum_c = 0.0, turned = 0.0;
  for (std::size_t k = 0; k < m.t.size(); ++k) {
    if (k > 0) turned += 0.5 * (m.w[k - 1] + m.w[k]) * (m.t[k] - m.t[k - 1]);
    if (!known[k]) continue;
    sum_s += speed[k] * std::sin(m.th[k] - turned);
    sum_c += speed[k] * std::cos(m.th[k] - turned);
  }
  if (!(sum_s != 0.0 || sum_c != 0.0)) return m.th.front();
  return m.th.front() + wrap_pi(std::atan2(sum_s, sum_c) - m.th.front());
}

Motion reference_motion(const Reference& ref, const ScenarioFromTrackOptions& o) {
  Motion m;
  const double t0 = ref.t.front(), span = ref.t.back() - t0;
  const double last_k = std::floor(span * o.knot_rate_hz + 1e-9);
  for (double k = 0; k <= last_k; k += 1.0) m.t.push_back(k / o.knot_rate_hz);
  if (span - m.t.back() > 1e-6) m.t.push_back(span);
  const std::size_t n = m.t.size();
  m.x.resize(n), m.y.resize(n), m.th.resize(n), m.v.resize(n), m.w.resize(n);
  const bool have_th = !ref.th.empty();
  std::vector<const std::vector<double>*> series = {&ref.x, &ref.y};
  if (have_th) series.push_back(&ref.th);
  std::vector<bool> heading_known(n, have_th);
  std::vector<double> vx(n), vy(n), speed(n, 0.0);
  const double half = ref.fixes ? o.fixes_half_window_s : o.half_window_s;
  for (std::size_t k = 0; k < n; ++k) {
    const double tc = t0 + m.t[k];
    const auto [lo, hi] = window_at(ref.t, tc, half, o.min_fit_points);
    const std::vector<Local> f = fit_at(ref.t, series, lo, hi, tc);
    m.x[k] = f[0].f, m.y[k] = f[1].f;
    vx[k] = f[0].d1, vy[k] = f[1].d1;
    if (have_th) {
      m.th[k] = f[2].f;
      m.w[k] = f[2].d1;
      continue;
    }
    const double sp2 = vx[k] * vx[k] + vy[k] * vy[k];
    const double se = std::hypot(f[0].se1, f[1].se1);
    if (sp2 > 0.0 && std::sqrt(sp2) >= std::max(o.min_speed_m_s, 3.0 * se)) {
      heading_known[k] = true;
      m.th[k] = std::atan2(vy[k], vx[k]);
      speed[k] = std::sqrt(sp2);
    }
  }
  if (!have_th) {  // hold the heading while slow; before the first known one, use it
    const auto first = std::find(heading_known.begin(), heading_known.end(), true);
    double prev = first == heading_known.end() ? 0.0
                                               : m.th[static_cast<std::size_t>(first - heading_known.begin())];
    for (std::size_t k = 0; k < n; ++k) {
      m.th[k] = heading_known[k] ? prev + wrap_pi(m.th[k] - prev) : prev;
      prev = m.th[k];
    }
    // w: central differences of the heading over the knots (they sum up to
    // the heading change, so the re-driven heading does not drift the way an
    // integrated curvature estimate would); 0 next to an unknown heading.
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? k : k + 1;
      m.w[k] = b > a && heading_known[a] && heading_known[b] ? (m.th[b] - m.th[a]) / (m.t[b] - m.t[a]) : 0.0;
    }
  }
  m.start_th = have_th ? m.th.front() : consensus_start_heading(m, heading_known, speed);
  for (std::size_t k = 0; k < n; ++k) m.v[k] = vx[k] * std::cos(m.th[k]) + vy[k] * std::sin(m.th[k]);
  return m;
}

// d f / d t at each knot: central differences, one-sided at the ends.
std::vector<double> rate_of(const std::vector<double>& t, const std::vector<double>& f) {
  const std::size_t n = f.size();
  std::vector<double> d(n, 0.0);
  if (n < 2) return d;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? k : k + 1;
    d[k] = (f[b] - f[a]) / (t[b] - t[a]);
  }
  return d;
}

// Rim speed u -> z = R_true*omega with u = z*(1 + c*z^2) (speed_radius).
double solve_speed_radius(double u, double c) {
  double z = u;
  for (int it = 0; it < 50; ++it) {
    const double f = z + c * z * z * z - u, df = 1.0 + 3.0 * c * z * z;
    if (!(df > 1e-3)) return u;  // beyond the monotone range (validate_scenario keeps us off it)
    const double step = f / df;
    z -= step;
    if (std::abs(step) <= 1e-15 * (1.0 + std::abs(z))) break;
  }
  return z;
}

// Commands that make the robot with effects `fx` drive `m` (docs/simulator.md,
// "Re-driving a track", "Commands").
std::vector<VelocityKnot> invert_effects(const Motion& m, const RobotParams& r, const Effects& fx) {
  const std::size_t n = m.t.size();
  const double D = r.wheel_base_m, D_true = D * (fx.wheel_base_error ? fx.wheel_base_error->scale : 1.0);
  std::array<std::vector<double>, 2> g;  // [0] left, [1] right: ground -> rim speed -> wheel rate
  g[0].resize(n), g[1].resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    g[0][k] = m.v[k] - m.w[k] * D_true / 2.0;
    g[1][k] = m.v[k] + m.w[k] * D_true / 2.0;
    if (const auto& z = fx.slip_zone) {  // the box is in the recording's frame, as m.x, m.y
      if (m.x[k] >= z->x0 && m.x[k] <= z->x1 && m.y[k] >= z->y0 && m.y[k] <= z->y1) {
        g[0][k] /= 1.0 - z->s_l;
        g[1][k] /= 1.0 - z->s_r;
      }
    }
  }
  for (int side = 0; side < 2; ++side) {
    auto& u = g[static_cast<std::size_t>(side)];
    if (fx.longitudinal_slip) {
      const std::vector<double> du = rate_of(m.t, u);
      for (std::size_t k = 0; k < n; ++k)
        u[k] /= 1.0 - std::min(0.5, fx.longitudinal_slip->k * std::abs(du[k]));
    }
    const double R_nom = side == 0 ? r.wheel_radius_left_m : r.wheel_radius_right_m;
    for (std::size_t k = 0; k < n; ++k) {
      double R = R_nom;
      if (fx.radius_error) R *= side == 0 ? fx.radius_error->scale_l : fx.radius_error->scale_r;
      if (fx.radius_step && m.t[k] >= fx.radius_step->t)
        R *= side == 0 ? fx.radius_step->scale_l : fx.radius_step->scale_r;
      const double z = fx.speed_radius ? solve_speed_radius(u[k], fx.speed_radius->c) : u[k];
      u[k] = z / R;  // wheel rate [rad/s]
    }
    if (fx.actuator_lag) {
      const std::vector<double> dom = rate_of(m.t, u);
      for (std::size_t k = 0; k < n; ++k) u[k] += fx.actuator_lag->tau * dom[k];
    }
  }
  std::vector<VelocityKnot> knots(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double rl = r.wheel_radius_left_m * g[0][k], rr = r.wheel_radius_right_m * g[1][k];
    knots[k] = {m.t[k], 0.5 * (rr + rl), (rr - rl) / D};
  }
  return knots;
}

// A finite metadata number (> 0 or >= 0), else nullopt.
std::optional<double> meta_number(const tracks::TrackMeta& meta, std::string_view key, bool positive) {
  const auto text = meta.get(key);
  if (!text) return std::nullopt;
  std::string_view s = *text;
  double x = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(x) || x < 0.0 || (positive && x == 0.0))
    return std::nullopt;
  return x;
}

RobotParams robot_of(const tracks::Track& track) {
  const tracks::TrackMeta& meta = track.meta();
  RobotParams r;
  if (meta.wheel_radius_left_m) r.wheel_radius_left_m = *meta.wheel_radius_left_m;
  if (meta.wheel_radius_right_m) r.wheel_radius_right_m = *meta.wheel_radius_right_m;
  if (meta.wheel_base_m) r.wheel_base_m = *meta.wheel_base_m;
  if (meta.ticks_per_rev) r.ticks_per_rev = *meta.ticks_per_rev;
  const std::array<std::tuple<std::string_view, double*, bool>, 8> extra = {
      {{"sim.robot.mass_kg", &r.mass_kg, false},
       {"sim.robot.yaw_inertia_kg_m2", &r.yaw_inertia_kg_m2, false},
       {"sim.robot.wheel_inertia_kg_m2", &r.wheel_inertia_kg_m2, false},
       {"sim.robot.viscous_friction_nm_s", &r.viscous_friction_nm_s, false},
       {"sim.robot.coulomb_friction_nm", &r.coulomb_friction_nm, false},
       {"sim.robot.coulomb_smoothing_rad_s", &r.coulomb_smoothing_rad_s, true},
       {"sim.robot.torque_constant_nm_per_a", &r.torque_constant_nm_per_a, true},
       {"sim.robot.coil_resistance_ohm", &r.coil_resistance_ohm, false}}};
  for (const auto& [key, field, positive] : extra)
    if (const auto x = meta_number(meta, key, positive)) *field = *x;
  return r;
}

// Sensor rates and noise (docs/simulator.md, "Re-driving a track", "Sensors").
class SensorBuilder {
 public:
  SensorBuilder(const tracks::Track& track, double step_s) : track_(track), sps_(std::round(1.0 / step_s)) {}

  // Times of the rows where any of `cols` (or the ticks) has a sample.
  std::vector<double> rows(std::initializer_list<tracks::Col> cols, bool ticks = false) const {
    std::vector<double> t;
    for (std::size_t i = 0; i < track_.size(); ++i) {
      bool any = ticks && track_.has_ticks() && track_.ticks_l()[i] != tracks::kNoTick;
      for (tracks::Col c : cols) any = any || track_.at(c, i);
      if (any) t.push_back(track_.t()[i]);
    }
    return t;
  }

  // 1 / median period, the period snapped to whole steps; `fallback_hz` (also
  // snapped) with fewer than 2 samples.
  double rate_hz(const std::vector<double>& t, double fallback_hz) const {
    const double period = t.size() >= 2 ? core::median_period_s(t, core::MedianRule::upper_middle)
                                        : 1.0 / fallback_hz;
    const double steps = std::max(1.0, std::round(period * sps_));
    return sps_ / steps;
  }

  double sigma(std::string_view key, double fallback) const {
    return meta_number(track_.meta(), key, false).value_or(fallback);
  }

  // sqrt(median) of a variance column's non-negative samples, else fallback.
  double sigma_from_variance(tracks::Col c, double fallback) const {
    std::vector<double> v;
    for (double x : track_.col(c))
      if (std::isfinite(x) && x >= 0.0) v.push_back(x);
    if (v.empty()) return fallback;
    return std::sqrt(core::median(std::move(v), core::MedianRule::upper_middle));
  }

  SensorParams build() const {
    const tracks::Track& tr = track_;
    SensorParams s;
    const SensorParams def;
    s.encoders.enabled = tr.has_ticks() || tr.has_wheel_rates();
    s.encoders.omega = tr.has_wheel_rates();
    if (s.encoders.enabled)
      s.encoders.rate_hz = rate_hz(rows({tracks::Col::omega_l, tracks::Col::omega_r}, true),
                                   def.encoders.rate_hz);
    s.commands.enabled = tr.has(tracks::Col::v_cmd) || tr.has(tracks::Col::w_cmd);
    if (s.commands.enabled)
      s.commands.rate_hz = rate_hz(rows({tracks::Col::v_cmd, tracks::Col::w_cmd}), def.commands.rate_hz);
    s.gyro.enabled = tr.has(tracks::Col::gyro_z);
    if (s.gyro.enabled) s.gyro.rate_hz = rate_hz(rows({tracks::Col::gyro_z}), def.gyro.rate_hz);
    s.gyro.sigma_rad_s = sigma("sim.gyro_sigma_rad_s", def.gyro.sigma_rad_s);
    s.power.enabled = tr.has(tracks::Col::power_l) || tr.has(tracks::Col::power_r);
    if (s.power.enabled)
      s.power.rate_hz = rate_hz(rows({tracks::Col::power_l, tracks::Col::power_r}), def.power.rate_hz);
    s.power.sigma_w = sigma("sim.power_sigma_w", def.power.sigma_w);
    s.ext_velocity.enabled = tr.has(tracks::Col::v_ext) || tr.has(tracks::Col::w_ext);
    if (s.ext_velocity.enabled)
      s.ext_velocity.rate_hz = rate_hz(rows({tracks::Col::v_ext, tracks::Col::w_ext}),
                                       def.ext_velocity.rate_hz);
    s.ext_velocity.sigma_v_m_s = sigma(
        "sim.ext_sigma_v_m_s", sigma_from_variance(tracks::Col::v_ext_var, def.ext_velocity.sigma_v_m_s));
    s.ext_velocity.sigma_w_rad_s = sigma(
        "sim.ext_sigma_w_rad_s", sigma_from_variance(tracks::Col::w_ext_var, def.ext_velocity.sigma_w_rad_s));
    s.aps.enabled = tr.has(tracks::Col::aps_x) || tr.has(tracks::Col::aps_y);
    if (s.aps.enabled) s.aps.rate_hz = rate_hz(rows({tracks::Col::aps_x, tracks::Col::aps_y}), def.aps.rate_hz);
    s.aps.sigma_m = sigma("sim.aps_sigma_m", def.aps.sigma_m);
    s.ground_truth.enabled = true;
    if (tr.has(tracks::Col::gt_x) || tr.has(tracks::Col::gt_y) || tr.has(tracks::Col::gt_theta)) {
      s.ground_truth.rate_hz = rate_hz(rows({tracks::Col::gt_x, tracks::Col::gt_y, tracks::Col::gt_theta}),
                                       def.ground_truth.rate_hz);
    } else {
      double fastest = 0.0;
      for (const auto& [on, rate] :
           {std::pair{s.encoders.enabled, s.encoders.rate_hz},
            std::pair{s.commands.enabled, s.commands.rate_hz}, std::pair{s.gyro.enabled, s.gyro.rate_hz},
            std::pair{s.power.enabled, s.power.rate_hz},
            std::pair{s.ext_velocity.enabled, s.ext_velocity.rate_hz}, std::pair{s.aps.enabled, s.aps.rate_hz}})
        if (on) fastest = std::max(fastest, rate);
      s.ground_truth.rate_hz = fastest > 0.0 ? fastest : rate_hz({}, def.ground_truth.rate_hz);
    }
    s.ground_truth.sigma_m = sigma("sim.gt_sigma_m", def.ground_truth.sigma_m);
    s.ground_truth.sigma_rad = sigma("sim.gt_sigma_rad", def.ground_truth.sigma_rad);
    return s;
  }

 private:
  const tracks::Track& track_;
  double sps_;  // steps per second
};

}  // namespace

bool ScenarioFromTrackOptions::IsValid(std::string* why) const {
  if (!(std::isfinite(knot_rate_hz) && knot_rate_hz > 0.0 && knot_rate_hz <= 1000.0))
    return core::invalid(why, fmt::format("knot_rate_hz = {}; expected a rate in (0, 1000] Hz", knot_rate_hz));
  if (!(std::isfinite(half_window_s) && half_window_s > 0.0))
    return core::invalid(why, fmt::format("half_window_s = {}; expected a number > 0 [s]", half_window_s));
  if (!(std::isfinite(fixes_half_window_s) && fixes_half_window_s > 0.0))
    return core::invalid(why, fmt::format("fixes_half_window_s = {}; expected a number > 0 [s]",
                                          fixes_half_window_s));
  if (min_fit_points < 4)
    return core::invalid(why, fmt::format("min_fit_points = {}; expected at least 4", min_fit_points));
  if (!(std::isfinite(min_speed_m_s) && min_speed_m_s >= 0.0))
    return core::invalid(why, fmt::format("min_speed_m_s = {}; expected a number >= 0 [m/s]", min_speed_m_s));
  const double inv = 1.0 / step_s;
  if (!(std::isfinite(step_s) && step_s > 0.0 && step_s <= 0.1 && inv <= 1e7 &&
        std::abs(inv - std::round(inv)) <= 1e-9 * std::round(inv)))
    return core::invalid(
        why, fmt::format("step_s = {}; expected a step in (0, 0.1] s whose inverse is a whole number", step_s));
  return true;
}

Scenario scenario_from_track(const tracks::Track& track, const std::vector<std::string>& effect_specs,
                             const ScenarioFromTrackOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("scenario_from_track: " + why);
  Effects fx;
  for (const std::string& text : effect_specs) {
    EffectSpec spec;
    spec = parse_effect_spec(text);  // its message already quotes the spec
    try {
      apply_effect(fx, spec);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("effect '{}': {}", text, e.what()));
    }
  }

  const Reference ref = reference_of(track);
  const double span_s = ref.t.back() - ref.t.front();
  if (!(span_s / options.step_s <= kMaxSimSteps))
    throw std::invalid_argument(fmt::format("track '{}': the reference spans {:.6g} s = {:.3g} steps of {} s; "
                                            "expected at most {:.3g} steps (the simulator's limit)",
                                            track.name(), span_s, span_s / options.step_s, options.step_s,
                                            kMaxSimSteps));
  if (fx.radius_step) fx.radius_step->t = std::max(0.0, fx.radius_step->t - ref.t.front());

  Scenario sc;
  sc.name = (track.name().empty() ? std::string("track") : track.name()) + "-corrected";
  sc.seed = options.seed;
  sc.step_s = options.step_s;
  sc.robot = robot_of(track);
  if (const auto a = meta_number(track.meta(), "sim.max_accel_m_s2", true)) sc.motion.max_accel_m_s2 = *a;
  if (const auto a = meta_number(track.meta(), "sim.max_angular_accel_rad_s2", true))
    sc.motion.max_angular_accel_rad_s2 = *a;
  sc.sensors = SensorBuilder(track, options.step_s).build();
  sc.effects = fx;
  const Motion m = reference_motion(ref, options);
  sc.motion.start_x_m = m.x.front();
  sc.motion.start_y_m = m.y.front();
  sc.motion.start_theta_rad = m.start_th;
  sc.motion.knots = invert_effects(m, sc.robot, fx);

  if (!validate_scenario(sc, &why))
    throw std::invalid_argument(fmt::format("track '{}': the corrected scenario is not valid: {}", track.name(),
                                            why));
  return sc;
}

}  // namespace odotune::sim

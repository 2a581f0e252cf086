#include <odotune/diagnose/effect_model.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>

#include <odotune/core/why.h>
#include <odotune/sim/effects.h>

namespace odotune::diagnose {

namespace {

const sim::EffectInfo& info(Effect e) {
  const auto& table = sim::effect_table();
  if (table.size() != static_cast<std::size_t>(kNumEffects))
    throw std::logic_error(fmt::format("effect table has {} effects; diagnose expects {}", table.size(),
                                       kNumEffects));
  return table[static_cast<std::size_t>(e)];
}

int param_index(Effect e, std::string_view param) {
  const auto& ps = info(e).params;
  for (std::size_t i = 0; i < ps.size(); ++i)
    if (ps[i].name == param) return static_cast<int>(i);
  throw std::invalid_argument(fmt::format("effect {} has no parameter '{}'; valid parameters: {}", info(e).name,
                                          param, sim::param_names(info(e))));
}

// Local quadratic least-squares fit of (t, s) around tc over nodes with
// |t - tc| <= half; returns the second derivative, or NaN with < 3 nodes.
double local_second_derivative(const std::vector<double>& t, const std::vector<double>& s, std::size_t lo,
                               std::size_t hi, double tc) {
  if (hi - lo < 3) return std::nan("");
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  const double s0 = s[lo];
  for (std::size_t j = lo; j < hi; ++j) {
    const double x = t[j] - tc;
    const Eigen::Vector3d phi(1.0, x, x * x);
    A += phi * phi.transpose();
    b += phi * (s[j] - s0);
  }
  const Eigen::Vector3d c = A.ldlt().solve(b);
  return std::isfinite(c(2)) ? 2.0 * c(2) : std::nan("");
}

// Nominal rim acceleration per interval: local quadratic fit of S around the
// interval's midpoint over +-half seconds (at least the interval's own nodes
// and their neighbours); falls back to the difference of the node speeds.
std::vector<double> rim_acceleration(const std::vector<double>& t, const std::vector<double>& s,
                                     const std::vector<double>& u, double half) {
  const std::size_t n = t.size();
  std::vector<double> a(n - 1, 0.0);
  std::size_t lo = 0, hi = 0;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double tc = 0.5 * (t[k] + t[k + 1]);
    while (lo < n && t[lo] < tc - half) ++lo;
    while (hi < n && t[hi] <= tc + half) ++hi;
    const std::size_t l = std::min(lo, k > 0 ? k - 1 : 0);
    const std::size_t h = std::max(hi, std::min(n, k + 3));
    const double v = local_second_derivative(t, s, l, h, tc);
    a[k] = std::isfinite(v) ? v : (u[k + 1] - u[k]) / (t[k + 1] - t[k]);
  }
  return a;
}

OdoSeries make_series(const DiagInput& in, bool from_commands, const ModelOptions& opt) {
  OdoSeries d;
  d.from_commands = from_commands;
  d.t_s = in.odo_t_s;
  const std::size_t n = d.t_s.size();
  d.s_l_m.assign(n, 0.0), d.s_r_m.assign(n, 0.0), d.u_l_mps.assign(n, 0.0), d.u_r_mps.assign(n, 0.0);
  d.wheel_base_m = in.wheel_base_m > 0.0 ? in.wheel_base_m : 1.0;
  if (from_commands) {
    const bool body = in.odometry == OdometryKind::body_velocity;
    const auto& v = body ? in.v_mps : in.cmd_v_mps;
    const auto& w = body ? in.w_radps : in.cmd_w_radps;
    for (std::size_t k = 0; k < n; ++k) {
      d.u_l_mps[k] = v[k] - 0.5 * w[k] * d.wheel_base_m;
      d.u_r_mps[k] = v[k] + 0.5 * w[k] * d.wheel_base_m;
      if (k > 0) {
        const double h = d.t_s[k] - d.t_s[k - 1];
        d.s_l_m[k] = d.s_l_m[k - 1] + 0.5 * h * (d.u_l_mps[k - 1] + d.u_l_mps[k]);
        d.s_r_m[k] = d.s_r_m[k - 1] + 0.5 * h * (d.u_r_mps[k - 1] + d.u_r_mps[k]);
      }
    }
  } else {
    for (std::size_t k = 0; k < n; ++k) {
      d.s_l_m[k] = in.radius_l_m * in.phi_l_rad[k];
      d.s_r_m[k] = in.radius_r_m * in.phi_r_rad[k];
    }
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t a = k > 0 ? k - 1 : 0, b = std::min(n - 1, k + 1);
      const double h = d.t_s[b] - d.t_s[a];
      d.u_l_mps[k] = (d.s_l_m[b] - d.s_l_m[a]) / h;
      d.u_r_mps[k] = (d.s_r_m[b] - d.s_r_m[a]) / h;
    }
  }
  d.a_l_mps2 = rim_acceleration(d.t_s, d.s_l_m, d.u_l_mps, opt.accel_half_window_s);
  d.a_r_mps2 = rim_acceleration(d.t_s, d.s_r_m, d.u_r_mps, opt.accel_half_window_s);
  return d;
}

}  // namespace

std::string_view effect_name(Effect e) { return info(e).name; }

Effect effect_from_name(std::string_view name) {
  const auto& table = sim::effect_table();
  for (std::size_t i = 0; i < table.size() && i < static_cast<std::size_t>(kNumEffects); ++i)
    if (table[i].name == name) return static_cast<Effect>(i);
  throw std::invalid_argument(fmt::format("unknown effect '{}'; valid effects: {}", name, sim::effect_names()));
}

std::string_view effect_description(Effect e) {
  switch (e) {
    case Effect::radius_error: return "everywhere the wheels roll: travel off by a constant ratio per wheel";
    case Effect::wheel_base_error: return "whenever the robot turns: heading change off by a constant ratio";
    case Effect::radius_step: return "after the step time: a wheel's effective radius changed";
    case Effect::speed_radius: return "growing with wheel speed: faster wheels travel further per turn";
    case Effect::lateral_skid: return "in turns taken at speed: the body slides outward, growing with |v*w|";
    case Effect::longitudinal_slip: return "while accelerating or braking: the wheels slip";
    case Effect::slip_zone: return "inside one region of the floor: the wheels slip there";
    case Effect::gyro_bias: return "at all times, also at rest: the gyro's heading drifts at a constant rate";
    case Effect::gyro_scale: return "while turning: the gyro's heading error grows with the turn rate";
    case Effect::actuator_lag: return "when the commands change: the body follows them late";
    case Effect::time_offset: return "when the velocities change: the odometry's time stamps are shifted";
    case Effect::odometry_bias:
      return "at all times, also at rest: the odometry reads its body velocities with a constant offset";
  }
  return "";
}

EffectSet EffectSet::parse(const std::vector<std::string>& specs) {
  EffectSet set;
  for (const auto& text : specs) {
    const sim::EffectSpec spec = sim::parse_effect_spec(text);
    const Effect e = effect_from_name(spec.name);
    set.enable(e);
    for (const auto& [param, value] : spec.values) set.set(e, param, value);
  }
  return set;
}

bool EffectSet::empty() const {
  return std::all_of(p_.begin(), p_.end(), [](const auto& v) { return v.empty(); });
}

EffectSet& EffectSet::enable(Effect e) {
  auto& v = p_[static_cast<int>(e)];
  if (v.empty())
    for (const auto& p : info(e).params) v.push_back(p.default_value);
  return *this;
}

EffectSet& EffectSet::disable(Effect e) {
  p_[static_cast<int>(e)].clear();
  return *this;
}

EffectSet& EffectSet::set(Effect e, std::string_view param, double value) {
  if (!on(e))
    throw std::invalid_argument(fmt::format("effect {} is off; enable it before setting {}", effect_name(e),
                                            param));
  const int i = param_index(e, param);
  const auto& pi = info(e).params[static_cast<std::size_t>(i)];
  std::string why;
  if (value != pi.default_value && !sim::check_param(info(e), pi, value, &why))
    throw std::invalid_argument(why);
  p_[static_cast<int>(e)][static_cast<std::size_t>(i)] = value;
  return *this;
}

double EffectSet::get(Effect e, std::string_view param) const {
  if (!on(e)) throw std::invalid_argument(fmt::format("effect {} is off", effect_name(e)));
  return p_[static_cast<int>(e)][static_cast<std::size_t>(param_index(e, param))];
}

std::string EffectSet::to_string() const {
  std::string out;
  for (int e = 0; e < kNumEffects; ++e) {
    if (p_[e].empty()) continue;
    const auto& ei = info(static_cast<Effect>(e));
    out += fmt::format("{}{}", out.empty() ? "" : "; ", ei.name);
    for (std::size_t i = 0; i < p_[e].size(); ++i)
      out += fmt::format("{}{}={}", i == 0 ? ":" : ",", ei.params[i].name, p_[e][i]);
  }
  return out.empty() ? "none" : out;
}

std::vector<ParamSlot> param_layout(const EffectSet& set) {
  std::vector<ParamSlot> out;
  for (int e = 0; e < kNumEffects; ++e) {
    const auto eff = static_cast<Effect>(e);
    if (!set.on(eff)) continue;
    const auto& ei = info(eff);
    for (std::size_t i = 0; i < ei.params.size(); ++i) {
      const auto& p = ei.params[i];
      const bool fixed = eff == Effect::gyro_bias || eff == Effect::gyro_scale ||
                         (eff == Effect::radius_step && p.name == "t") ||
                         (eff == Effect::slip_zone && p.name != "s_l" && p.name != "s_r");
      const double lower = p.min_exclusive ? p.min + 1e-6 * (p.max - p.min) : p.min;
      out.push_back({eff, static_cast<int>(i), fmt::format("{}.{}", ei.name, p.name), lower, p.max,
                     p.default_value, !fixed});
    }
  }
  return out;
}

std::vector<double> pack(const EffectSet& set) {
  std::vector<double> out;
  for (int e = 0; e < kNumEffects; ++e)
    for (double v : set.params(static_cast<Effect>(e))) out.push_back(v);
  return out;
}

EffectSet unpack(const EffectSet& structure, const std::vector<double>& values) {
  EffectSet out = structure;
  std::size_t j = 0;
  for (const ParamSlot& s : param_layout(structure)) {
    if (j >= values.size())
      throw std::invalid_argument(fmt::format("unpack: {} values for a layout of {} or more", values.size(),
                                              j + 1));
    out.set(s.effect, info(s.effect).params[static_cast<std::size_t>(s.index)].name, values[j++]);
  }
  return out;
}

double corrected_gyro_rate(const EffectSet& set, double gyro_radps) {
  const double b = set.on(Effect::gyro_bias) ? set.get(Effect::gyro_bias, "b") : 0.0;
  const double s = set.on(Effect::gyro_scale) ? set.get(Effect::gyro_scale, "s") : 1.0;
  return corrected_gyro_rate(gyro_radps, b, s);
}

bool ModelOptions::IsValid(std::string* why) const {
  if (!(std::isfinite(accel_half_window_s) && accel_half_window_s > 0.0 && accel_half_window_s <= 10.0))
    return core::invalid(why, fmt::format("accel_half_window_s = {}; expected a number in (0, 10] s",
                                          accel_half_window_s));
  if (!(std::isfinite(lag_lead_in_s) && lag_lead_in_s >= 0.0 && lag_lead_in_s <= 600.0))
    return core::invalid(why,
                         fmt::format("lag_lead_in_s = {}; expected a number in [0, 600] s", lag_lead_in_s));
  return true;
}

EffectModel::EffectModel(const DiagInput& input, const EffectSet& structure, const ModelOptions& opt)
    : structure_(structure), layout_(param_layout(structure)), opt_(opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("model options: " + why);
  const bool body = input.odometry == OdometryKind::body_velocity;
  const std::size_t n = input.odo_t_s.size();
  if (n < 2)
    throw std::invalid_argument(fmt::format("track '{}': {} odometry sample(s); expected at least 2",
                                            input.track_name, n));
  const bool lag = structure.on(Effect::actuator_lag);
  if (lag && !body && input.cmd_v_mps.size() != n)
    throw std::invalid_argument(
        fmt::format("track '{}': actuator_lag needs commands (v_cmd, w_cmd); the track has wheel odometry only",
                    input.track_name));
  if (body ? (input.v_mps.size() != n || input.w_radps.size() != n)
           : (input.phi_l_rad.size() != n || input.phi_r_rad.size() != n))
    throw std::invalid_argument(fmt::format("track '{}': odometry columns differ in length from "
                                            "odo_t_s ({} samples)",
                                            input.track_name, n));
  series_ = make_series(input, body || lag, opt);

  auto at = [this](Effect e, std::string_view p) {
    const int want = param_index(e, p);
    for (std::size_t j = 0; j < layout_.size(); ++j)
      if (layout_[j].effect == e && layout_[j].index == want) return static_cast<int>(j);
    return -1;
  };
  idx_.re_l = at(Effect::radius_error, "scale_l");
  idx_.re_r = at(Effect::radius_error, "scale_r");
  idx_.wb = at(Effect::wheel_base_error, "scale");
  idx_.rs_t = at(Effect::radius_step, "t");
  idx_.rs_l = at(Effect::radius_step, "scale_l");
  idx_.rs_r = at(Effect::radius_step, "scale_r");
  idx_.sr_c = at(Effect::speed_radius, "c");
  idx_.skid_k = at(Effect::lateral_skid, "k");
  idx_.slip_k = at(Effect::longitudinal_slip, "k");
  idx_.zx0 = at(Effect::slip_zone, "x0");
  idx_.zx1 = at(Effect::slip_zone, "x1");
  idx_.zy0 = at(Effect::slip_zone, "y0");
  idx_.zy1 = at(Effect::slip_zone, "y1");
  idx_.z_l = at(Effect::slip_zone, "s_l");
  idx_.z_r = at(Effect::slip_zone, "s_r");
  idx_.tau = at(Effect::actuator_lag, "tau");
  idx_.dt = at(Effect::time_offset, "dt");
  idx_.ob_v = at(Effect::odometry_bias, "b_v");
  idx_.ob_w = at(Effect::odometry_bias, "b_w");
}

}  // namespace odotune::diagnose

#include <odotune/sim/effects.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>

#include <odotune/core/why.h>

namespace odotune::sim {

namespace {

constexpr double kBig = 1e4;  // bound of world coordinates [m] accepted for slip_zone

// Ranges: wide enough for any plausible physical value, narrow enough that the
// simulated robot still behaves like a robot (a radius scale of 3 is a typo).
// Defaults are the no-op values of optional parameters.
const std::vector<EffectInfo> kTable = {
    {"radius_error",
     "true radii are R_nom*scale (tyre wear, pressure, a mis-measured wheel)",
     {{"scale_l", "1", "true/nominal left radius", 0.5, 1.5, false, false, 1.0},
      {"scale_r", "1", "true/nominal right radius", 0.5, 1.5, false, false, 1.0}}},
    {"wheel_base_error",
     "true wheel base is D_nom*scale (contact patch not where assumed; scrub)",
     {{"scale", "1", "true/nominal wheel base", 0.5, 2.0, false, true, 1.0}}},
    {"radius_step",
     "from time t on, the true radii are multiplied by the scales",
     {{"t", "s", "time of the step", 0.0, 1e6, false, true, 0.0},
      {"scale_l", "1", "left radius factor from t on", 0.5, 1.5, false, false, 1.0},
      {"scale_r", "1", "right radius factor from t on", 0.5, 1.5, false, false, 1.0}}},
    {"speed_radius",
     "each wheel's effective radius is R*(1 + c*u^2), u its rim speed R*omega",
     {{"c", "s^2/m^2", "radius growth per squared rim speed", -0.1, 0.1, false, true, 0.0}}},
    {"lateral_skid",
     "the body slides outward in turns: v_y = -k*v*w",
     {{"k", "s", "lateral velocity per v*w", 0.0, 1.0, false, true, 0.0}}},
    {"longitudinal_slip",
     "wheel ground speed R*omega*(1 - s), s = min(0.5, k*|du/dt|)",
     {{"k", "s^2/m", "slip per rim acceleration", 0.0, 10.0, false, true, 0.0}}},
    {"slip_zone",
     "inside the box x0<=x<=x1, y0<=y<=y1, wheel ground speed R*omega*(1 - s)",
     {{"x0", "m", "box lower x (world)", -kBig, kBig, false, true, 0.0},
      {"x1", "m", "box upper x (world)", -kBig, kBig, false, true, 0.0},
      {"y0", "m", "box lower y (world)", -kBig, kBig, false, true, 0.0},
      {"y1", "m", "box upper y (world)", -kBig, kBig, false, true, 0.0},
      {"s_l", "1", "left wheel slip inside the box", 0.0, 0.9, false, false, 0.0},
      {"s_r", "1", "right wheel slip inside the box", 0.0, 0.9, false, false, 0.0}}},
    {"gyro_bias", "the gyro reads w + b", {{"b", "rad/s", "gyro bias", -1.0, 1.0, false, true, 0.0}}},
    {"gyro_scale", "the gyro reads s*w", {{"s", "1", "gyro scale factor", 0.5, 1.5, false, true, 1.0}}},
    {"actuator_lag",
     "true body velocities follow v_cmd, w_cmd through a first-order lag",
     {{"tau", "s", "time constant", 0.0, 5.0, true, true, 0.0}}},
    {"time_offset",
     "odometry columns stamped t were measured at t - dt",
     {{"dt", "s", "odometry delay (positive: late)", -1.0, 1.0, false, true, 0.0}}},
    // Both optional (an offset in one velocity alone is common), 0 = no offset;
    // 0.5 m/s or rad/s of apparent motion at rest is far beyond a plausible offset.
    {"odometry_bias",
     "the odometry's body velocities read v + b_v and w + b_w",
     {{"b_v", "m/s", "offset of the odometry's body speed", -0.5, 0.5, false, false, 0.0},
      {"b_w", "rad/s", "offset of the odometry's yaw rate", -0.5, 0.5, false, false, 0.0}}},
};

// Pointers to the parameter fields of effect `index` (table order) in `e`, or
// an empty vector if it is off. With `on`, switches it on first (fields keep
// whatever the struct holds; apply_effect then sets them all).
std::vector<double*> fields(Effects& e, std::size_t index, bool on) {
  auto get = [on](auto& opt) -> decltype(&*opt) {
    // Not opt.emplace(): clang 14 (clang-tidy) rejects emplace() of a nested struct with
    // default member initialisers; the value-initialised struct is the same.
    if (!opt && on) opt = std::remove_reference_t<decltype(*opt)>{};
    return opt ? &*opt : nullptr;
  };
  switch (index) {
    case 0:
      if (auto* p = get(e.radius_error)) return {&p->scale_l, &p->scale_r};
      break;
    case 1:
      if (auto* p = get(e.wheel_base_error)) return {&p->scale};
      break;
    case 2:
      if (auto* p = get(e.radius_step)) return {&p->t, &p->scale_l, &p->scale_r};
      break;
    case 3:
      if (auto* p = get(e.speed_radius)) return {&p->c};
      break;
    case 4:
      if (auto* p = get(e.lateral_skid)) return {&p->k};
      break;
    case 5:
      if (auto* p = get(e.longitudinal_slip)) return {&p->k};
      break;
    case 6:
      if (auto* p = get(e.slip_zone)) return {&p->x0, &p->x1, &p->y0, &p->y1, &p->s_l, &p->s_r};
      break;
    case 7:
      if (auto* p = get(e.gyro_bias)) return {&p->b};
      break;
    case 8:
      if (auto* p = get(e.gyro_scale)) return {&p->s};
      break;
    case 9:
      if (auto* p = get(e.actuator_lag)) return {&p->tau};
      break;
    case 10:
      if (auto* p = get(e.time_offset)) return {&p->dt};
      break;
    case 11:
      if (auto* p = get(e.odometry_bias)) return {&p->b_v, &p->b_w};
      break;
    default: break;
  }
  return {};
}

void switch_off(Effects& e, std::size_t index) {
  switch (index) {
    case 0: e.radius_error.reset(); break;
    case 1: e.wheel_base_error.reset(); break;
    case 2: e.radius_step.reset(); break;
    case 3: e.speed_radius.reset(); break;
    case 4: e.lateral_skid.reset(); break;
    case 5: e.longitudinal_slip.reset(); break;
    case 6: e.slip_zone.reset(); break;
    case 7: e.gyro_bias.reset(); break;
    case 8: e.gyro_scale.reset(); break;
    case 9: e.actuator_lag.reset(); break;
    case 10: e.time_offset.reset(); break;
    case 11: e.odometry_bias.reset(); break;
    default: break;
  }
}

std::size_t index_of(const EffectInfo& info) { return static_cast<std::size_t>(&info - kTable.data()); }

std::string_view trim_blank(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0u : 1u)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string unknown_effect_message(std::string_view name) {
  std::vector<std::string_view> names;
  names.reserve(kTable.size());
  for (const auto& e : kTable) names.push_back(e.name);
  const std::string guess = closest_name(name, names);
  return fmt::format("unknown effect '{}'{}; valid effects: {}", name,
                     guess.empty() ? "" : fmt::format(" (did you mean '{}'?)", guess), effect_names());
}

std::string unknown_param_message(const EffectInfo& e, std::string_view param) {
  std::vector<std::string_view> names;
  for (const auto& p : e.params) names.push_back(p.name);
  const std::string guess = closest_name(param, names);
  return fmt::format("effect {} has no parameter '{}'{}; valid parameters: {}", e.name, param,
                     guess.empty() ? "" : fmt::format(" (did you mean '{}'?)", guess), param_names(e));
}

bool check_cross(const Effects& e, std::string* why) {
  if (e.slip_zone && !(e.slip_zone->x0 < e.slip_zone->x1 && e.slip_zone->y0 < e.slip_zone->y1)) {
    return core::invalid(why,
                         fmt::format("slip_zone box is empty (x0 = {}, x1 = {}, y0 = {}, y1 = {}); expected "
                                     "x0 < x1 and y0 < y1",
                                     e.slip_zone->x0, e.slip_zone->x1, e.slip_zone->y0, e.slip_zone->y1));
  }
  return true;
}

}  // namespace

const std::vector<EffectInfo>& effect_table() { return kTable; }

const EffectInfo* find_effect(std::string_view name) {
  for (const auto& e : kTable)
    if (e.name == name) return &e;
  return nullptr;
}

const EffectParamInfo* find_param(const EffectInfo& effect, std::string_view param) {
  for (const auto& p : effect.params)
    if (p.name == param) return &p;
  return nullptr;
}

std::string effect_names() {
  std::string out;
  for (const auto& e : kTable) out += (out.empty() ? "" : ", ") + std::string(e.name);
  return out;
}

std::string param_names(const EffectInfo& effect) {
  std::string out;
  for (const auto& p : effect.params) out += (out.empty() ? "" : ", ") + std::string(p.name);
  return out;
}

std::string closest_name(std::string_view word, const std::vector<std::string_view>& candidates) {
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (auto c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) best_d = d, best = std::string(c);
  }
  const std::size_t limit = std::max<std::size_t>(1, word.size() / 3);
  return best_d <= limit ? best : std::string();
}

bool check_param(const EffectInfo& effect, const EffectParamInfo& param, double value, std::string* why) {
  const bool low_ok = param.min_exclusive ? value > param.min : value >= param.min;
  if (std::isfinite(value) && low_ok && value <= param.max) return true;
  return core::invalid(why, fmt::format("{}.{} = {} is out of range {}{}, {}]{}", effect.name, param.name,
                                        value, param.min_exclusive ? "(" : "[", param.min, param.max,
                                        param.unit == "1" ? "" : fmt::format(" {}", param.unit)));
}

EffectSpec parse_effect_spec(std::string_view text) {
  const std::string_view whole = trim_blank(text);
  const auto colon = whole.find(':');
  const std::string_view name = trim_blank(whole.substr(0, colon));
  auto fail = [&](const std::string& msg) {
    throw std::invalid_argument(fmt::format("effect '{}': {}", whole, msg));
  };
  if (name.empty())
    fail("missing effect name; expected NAME:PARAM=VALUE,... with NAME one of " + effect_names());
  const EffectInfo* info = find_effect(name);
  if (!info) fail(unknown_effect_message(name));
  EffectSpec spec{std::string(name), {}};
  if (colon == std::string_view::npos) return spec;
  std::string_view rest = whole.substr(colon + 1);
  while (!trim_blank(rest).empty()) {
    const auto comma = rest.find(',');
    const std::string_view item = trim_blank(rest.substr(0, comma));
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    const auto eq = item.find('=');
    if (eq == std::string_view::npos)
      fail(fmt::format("'{}' is not PARAM=VALUE; parameters of {}: {}", item, info->name, param_names(*info)));
    const std::string_view pname = trim_blank(item.substr(0, eq));
    const std::string_view vtext = trim_blank(item.substr(eq + 1));
    const EffectParamInfo* p = find_param(*info, pname);
    if (!p) fail(unknown_param_message(*info, pname));
    double value = 0.0;
    const auto [end, ec] = std::from_chars(vtext.data(), vtext.data() + vtext.size(), value);
    if (vtext.empty() || ec != std::errc() || end != vtext.data() + vtext.size())
      fail(fmt::format("{}.{} = '{}' is not a number; expected a value in {}{}, {}]", info->name, pname, vtext,
                       p->min_exclusive ? "(" : "[", p->min, p->max));
    std::string why;
    if (!check_param(*info, *p, value, &why)) fail(why);
    for (const auto& [k, v] : spec.values)
      if (k == pname) fail(fmt::format("parameter {} given twice", pname));
    spec.values.emplace_back(std::string(pname), value);
  }
  return spec;
}

void apply_effect(Effects& effects, const EffectSpec& spec) {
  const EffectInfo* info = find_effect(spec.name);
  if (!info) throw std::invalid_argument(unknown_effect_message(spec.name));
  const std::size_t idx = index_of(*info);
  Effects out = effects;  // all-or-nothing
  const bool was_on = !fields(out, idx, false).empty();
  std::vector<double*> f = fields(out, idx, true);
  if (!was_on)
    for (std::size_t i = 0; i < info->params.size(); ++i) *f[i] = info->params[i].default_value;
  std::vector<bool> given(info->params.size(), false);
  for (const auto& [pname, value] : spec.values) {
    const EffectParamInfo* p = find_param(*info, pname);
    if (!p) throw std::invalid_argument(unknown_param_message(*info, pname));
    std::string why;
    if (!check_param(*info, *p, value, &why)) throw std::invalid_argument(why);
    const auto i = static_cast<std::size_t>(p - info->params.data());
    *f[i] = value;
    given[i] = true;
  }
  if (!was_on)
    for (std::size_t i = 0; i < info->params.size(); ++i)
      if (info->params[i].required && !given[i])
        throw std::invalid_argument(
            fmt::format("effect {} needs parameter {} [{}] ({}); expected {}:{}=VALUE,...", info->name,
                        info->params[i].name, info->params[i].unit, info->params[i].meaning, info->name,
                        info->params[i].name));
  std::string why;
  if (!check_cross(out, &why)) throw std::invalid_argument(why);
  effects = out;
}

void remove_effect(Effects& effects, std::string_view name) {
  const EffectInfo* info = find_effect(name);
  if (!info) throw std::invalid_argument(unknown_effect_message(name));
  switch_off(effects, index_of(*info));
}

std::vector<EffectSpec> active_effects(const Effects& effects) {
  std::vector<EffectSpec> out;
  Effects copy = effects;  // fields() hands out mutable pointers; read them from a copy
  for (std::size_t i = 0; i < kTable.size(); ++i) {
    const auto f = fields(copy, i, false);
    if (f.empty()) continue;
    EffectSpec s{std::string(kTable[i].name), {}};
    for (std::size_t j = 0; j < f.size(); ++j)
      s.values.emplace_back(std::string(kTable[i].params[j].name), *f[j]);
    out.push_back(std::move(s));
  }
  return out;
}

std::string format_effect(const EffectSpec& spec) {
  std::string out = spec.name;
  for (std::size_t i = 0; i < spec.values.size(); ++i)
    out += fmt::format("{}{}={}", i == 0 ? ":" : ",", spec.values[i].first, spec.values[i].second);
  return out;
}

std::string format_effects(const Effects& effects) {
  std::string out;
  for (const auto& s : active_effects(effects)) out += (out.empty() ? "" : "; ") + format_effect(s);
  return out.empty() ? "none" : out;
}

bool validate_effects(const Effects& effects, std::string* why) {
  for (const auto& s : active_effects(effects)) {
    const EffectInfo* info = find_effect(s.name);
    for (const auto& [pname, value] : s.values)
      if (!check_param(*info, *find_param(*info, pname), value, why)) return false;
  }
  return check_cross(effects, why);
}

}  // namespace odotune::sim

// scenario_to_yaml (declared in odotune/formats/scenario_yaml.h): a Scenario as YAML text
// that parse_scenario reads back to the same fields.
//
// Written as careful text rather than with YAML::Emitter so that the layout is
// the one of the hand-written scenarios (one segment / knot per line, flow
// maps for small blocks). Numbers use fmt's "{}" for doubles, the shortest
// text that std::from_chars (the reader) turns back into the same double.
#include <cmath>
#include <cstddef>
#include <iterator>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <odotune/formats/scenario_yaml.h>
#include <odotune/sim/effects.h>
#include <odotune/sim/simulator.h>
#include <odotune/sim/slip_episodes.h>

namespace odotune::formats {

namespace {

using Entry = std::pair<std::string_view, std::string>;  // key, value text

// Shortest round-trip text of a finite number; throws for a non-finite one.
std::string num(std::string_view what, double x) {
  if (!std::isfinite(x))
    throw std::invalid_argument(fmt::format("scenario_to_yaml: {} = {}; expected a finite number", what, x));
  return fmt::format("{}", x);
}

std::string flag(bool b) { return b ? "true" : "false"; }

// "{a: 1, b: 2}"
std::string flow_map(const std::vector<Entry>& entries) {
  std::string s = "{";
  for (std::size_t i = 0; i < entries.size(); ++i)
    s += fmt::format("{}{}: {}", i ? ", " : "", entries[i].first, entries[i].second);
  return s + "}";
}

// A YAML double-quoted scalar: '"' and '\' escaped, ASCII control characters
// as \xNN (bytes >= 0x80, i.e. UTF-8, pass through).
std::string yaml_quoted(std::string_view text) {
  std::string s = "\"";
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      s += '\\';
      s += c;
    } else if (u < 0x20 || u == 0x7f) {
      s += fmt::format("\\x{:02x}", u);
    } else {
      s += c;
    }
  }
  return s + "\"";
}

void write_header(std::string& out, const std::string& header) {
  if (header.empty()) return;
  std::size_t begin = 0;
  while (begin <= header.size()) {
    std::size_t end = header.find('\n', begin);
    if (end == std::string::npos) end = header.size();
    std::string_view line(header.data() + begin, end - begin);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    out += line.empty() ? std::string("#\n") : fmt::format("# {}\n", line);
    begin = end + 1;
  }
  out += '\n';
}

void write_robot(std::string& out, const sim::RobotParams& r) {
  const std::vector<std::pair<std::string_view, double>> fields = {
      {"wheel_radius_left_m", r.wheel_radius_left_m},
      {"wheel_radius_right_m", r.wheel_radius_right_m},
      {"wheel_base_m", r.wheel_base_m},
      {"ticks_per_rev", r.ticks_per_rev},
      {"mass_kg", r.mass_kg},
      {"yaw_inertia_kg_m2", r.yaw_inertia_kg_m2},
      {"wheel_inertia_kg_m2", r.wheel_inertia_kg_m2},
      {"viscous_friction_nm_s", r.viscous_friction_nm_s},
      {"coulomb_friction_nm", r.coulomb_friction_nm},
      {"coulomb_smoothing_rad_s", r.coulomb_smoothing_rad_s},
      {"torque_constant_nm_per_a", r.torque_constant_nm_per_a},
      {"coil_resistance_ohm", r.coil_resistance_ohm}};
  out += "robot:\n";
  for (const auto& [key, value] : fields)
    out += fmt::format("  {}: {}\n", key, num(fmt::format("robot.{}", key), value));
}

std::string segment_line(const sim::Segment& s, std::size_t i) {
  const std::string p = fmt::format("motion.segments[{}].", i + 1);
  switch (s.kind) {
    case sim::Segment::Kind::straight:
      return "straight: " + flow_map({{"distance_m", num(p + "distance_m", s.distance_m)},
                                      {"speed_m_s", num(p + "speed_m_s", s.speed_m_s)}});
    case sim::Segment::Kind::arc:
      return "arc: " + flow_map({{"radius_m", num(p + "radius_m", s.radius_m)},
                                 {"angle_deg", num(p + "angle_deg", s.angle_deg)},
                                 {"speed_m_s", num(p + "speed_m_s", s.speed_m_s)}});
    case sim::Segment::Kind::spin:
      return "spin: " + flow_map({{"angle_deg", num(p + "angle_deg", s.angle_deg)},
                                  {"rate_deg_s", num(p + "rate_deg_s", s.rate_deg_s)}});
    case sim::Segment::Kind::stop:
      return "stop: " + flow_map({{"duration_s", num(p + "duration_s", s.duration_s)}});
  }
  throw std::invalid_argument(fmt::format("scenario_to_yaml: motion.segments[{}]: unknown kind", i + 1));
}

void write_motion(std::string& out, const sim::MotionParams& m) {
  out += "motion:\n";
  if (m.start_x_m != 0.0 || m.start_y_m != 0.0 || m.start_theta_rad != 0.0)
    out += fmt::format("  start: {}\n",
                       flow_map({{"x_m", num("motion.start.x_m", m.start_x_m)},
                                 {"y_m", num("motion.start.y_m", m.start_y_m)},
                                 {"theta_rad", num("motion.start.theta_rad", m.start_theta_rad)}}));
  out += fmt::format("  max_accel_m_s2: {}\n", num("motion.max_accel_m_s2", m.max_accel_m_s2));
  out += fmt::format("  max_angular_accel_rad_s2: {}\n",
                     num("motion.max_angular_accel_rad_s2", m.max_angular_accel_rad_s2));
  if (!m.segments.empty()) {
    out += "  segments:\n";
    for (std::size_t i = 0; i < m.segments.size(); ++i)
      out += fmt::format("    - {}\n", segment_line(m.segments[i], i));
  } else {
    out += "  knots:  # [t_s, v_m_s, w_rad_s], linear in between\n";
    for (std::size_t i = 0; i < m.knots.size(); ++i) {
      const sim::VelocityKnot& k = m.knots[i];
      const std::string p = fmt::format("motion.knots[{}].", i + 1);
      out += fmt::format("    - [{}, {}, {}]\n", num(p + "t_s", k.t_s), num(p + "v_m_s", k.v_m_s),
                         num(p + "w_rad_s", k.w_rad_s));
    }
  }
}

void write_sensors(std::string& out, const sim::SensorParams& s) {
  std::string_view sensor;  // for the messages of n()
  auto n = [&sensor](std::string_view key, double value) {
    return Entry{key, num(fmt::format("sensors.{}.{}", sensor, key), value)};
  };
  auto on = [](bool enabled) { return Entry{"enabled", flag(enabled)}; };
  auto line = [&out, &sensor](const std::vector<Entry>& entries) {
    out += fmt::format("  {}: {}\n", sensor, flow_map(entries));
  };
  out += "sensors:\n";
  sensor = "encoders";
  line({on(s.encoders.enabled),
        n("rate_hz", s.encoders.rate_hz),
        {"omega", flag(s.encoders.omega)},
        n("omega_resolution_rad_s", s.encoders.omega_resolution_rad_s)});
  sensor = "commands";
  line({on(s.commands.enabled), n("rate_hz", s.commands.rate_hz), n("resolution", s.commands.resolution)});
  sensor = "gyro";
  line({on(s.gyro.enabled), n("rate_hz", s.gyro.rate_hz), n("sigma_rad_s", s.gyro.sigma_rad_s),
        n("resolution_rad_s", s.gyro.resolution_rad_s)});
  sensor = "power";
  line({on(s.power.enabled), n("rate_hz", s.power.rate_hz), n("sigma_w", s.power.sigma_w),
        n("resolution_w", s.power.resolution_w)});
  sensor = "ext_velocity";
  line({on(s.ext_velocity.enabled), n("rate_hz", s.ext_velocity.rate_hz),
        n("sigma_v_m_s", s.ext_velocity.sigma_v_m_s), n("sigma_w_rad_s", s.ext_velocity.sigma_w_rad_s),
        n("resolution", s.ext_velocity.resolution)});
  sensor = "aps";
  line({on(s.aps.enabled), n("rate_hz", s.aps.rate_hz), n("sigma_m", s.aps.sigma_m),
        n("resolution_m", s.aps.resolution_m)});
  sensor = "ground_truth";
  line({on(s.ground_truth.enabled), n("rate_hz", s.ground_truth.rate_hz), n("sigma_m", s.ground_truth.sigma_m),
        n("sigma_rad", s.ground_truth.sigma_rad), n("resolution_m", s.ground_truth.resolution_m),
        n("resolution_rad", s.ground_truth.resolution_rad)});
}

void write_effects(std::string& out, const sim::Effects& fx) {
  const std::vector<sim::EffectSpec> active = sim::active_effects(fx);
  if (active.empty()) {
    out += "effects: {}\n";
    return;
  }
  out += "effects:\n";
  for (const sim::EffectSpec& e : active) {
    std::vector<Entry> entries;
    for (const auto& [param, value] : e.values)
      entries.emplace_back(param, num(fmt::format("effects.{}.{}", e.name, param), value));
    out += fmt::format("  {}: {}\n", e.name, flow_map(entries));
  }
}

void write_slip_episodes(std::string& out, const std::vector<sim::SlipEpisode>& episodes) {
  if (episodes.empty()) return;
  out += "slip_episodes:\n";
  for (std::size_t i = 0; i < episodes.size(); ++i) {
    const sim::SlipEpisode& e = episodes[i];
    const std::string p = fmt::format("slip_episodes[{}].", i + 1);
    std::vector<Entry> entries = {{"kind", std::string(sim::kind_name(e.kind))},
                                  {"wheel", std::string(sim::wheel_name(e.wheel))},
                                  {"t0_s", num(p + "t0_s", e.t0_s)},
                                  {"t1_s", num(p + "t1_s", e.t1_s)},
                                  {"s", num(p + "s", e.s)},
                                  {"ramp_s", num(p + "ramp_s", e.ramp_s)}};
    if (e.kind == sim::SlipEpisode::Kind::hold)
      entries.emplace_back("brake_nm", num(p + "brake_nm", e.brake_nm));
    out += fmt::format("  - {}\n", flow_map(entries));
  }
}

// terms: one flow map per term, ASCII names (odotune/sim/model_terms.h).
void write_terms(std::string& out, const std::vector<sim::ModelTerm>& terms) {
  if (terms.empty()) return;
  out += "terms:\n";
  for (std::size_t i = 0; i < terms.size(); ++i) {
    const sim::ModelTerm& m = terms[i];
    out += fmt::format("  - {}\n", flow_map({{"target", std::string(sim::target_name(m.target))},
                                             {"term", yaml_quoted(sim::term_name(m.target, m.basis, true))},
                                             {"coef", num(fmt::format("terms[{}].coef", i + 1), m.coef)}}));
  }
}

}  // namespace

std::string scenario_to_yaml(const sim::Scenario& sc, const std::string& header_comment) {
  if (sc.name.empty() || sc.name.find_first_of("\r\n") != std::string::npos)
    throw std::invalid_argument(
        fmt::format("scenario_to_yaml: the name is {}; expected a non-empty one-line text",
                    sc.name.empty() ? "empty" : "split by a line break"));
  if (sc.motion.segments.empty() && sc.motion.knots.empty())
    throw std::invalid_argument(
        "scenario_to_yaml: motion has neither segments nor knots; expected one of them");
  std::string why;
  if (!sim::validate_scenario(sc, &why)) throw std::invalid_argument("scenario_to_yaml: " + why);

  std::string out;
  write_header(out, header_comment);
  out += fmt::format("name: {}\n", yaml_quoted(sc.name));
  out += fmt::format("seed: {}\n", sc.seed);
  out += fmt::format("step_s: {}\n", num("step_s", sc.step_s));
  write_robot(out, sc.robot);
  write_motion(out, sc.motion);
  write_sensors(out, sc.sensors);
  write_effects(out, sc.effects);
  write_slip_episodes(out, sc.slip_episodes);
  write_terms(out, sc.terms);
  return out;
}

}  // namespace odotune::formats

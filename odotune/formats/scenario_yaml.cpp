#include <odotune/formats/scenario_yaml.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <variant>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <odotune/sim/effects.h>
#include <odotune/sim/model_terms.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/simulator.h>
#include <odotune/sim/slip_episodes.h>

namespace odotune::formats {

namespace {

constexpr std::uintmax_t kMaxFileBytes = 16u << 20;  // a scenario is a few kB
constexpr std::size_t kMaxSegments = 1'000'000;      // after expanding repeats
constexpr std::size_t kMaxKnots = 1'000'000;         // motion.knots entries
constexpr long kMaxRepeat = 100'000;
const std::vector<std::string_view> kTopKeys = {"name",    "seed",    "step_s",        "robot", "motion",
                                                "sensors", "effects", "slip_episodes", "terms"};

std::size_t line_of(const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  return m.is_null() || m.line < 0 ? 0 : static_cast<std::size_t>(m.line) + 1;
}

const char* kind_of(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "nothing";
  if (n.IsMap()) return "a map";
  if (n.IsSequence()) return "a list";
  return "a value";
}

// A field of a block: the YAML key and where its value goes.
struct Field {
  std::string_view key;
  std::variant<double*, bool*> target;
};

class Parser {
 public:
  explicit Parser(std::string file) : file_(std::move(file)) {}

  sim::Scenario parse(std::string_view text) {
    YAML::Node root;
    try {
      root = YAML::Load(std::string(text));
    } catch (const YAML::ParserException& e) {
      const std::size_t line = e.mark.is_null() || e.mark.line < 0 ? 0
                                                                   : static_cast<std::size_t>(e.mark.line) + 1;
      throw ScenarioError(file_, line, fmt::format("YAML syntax error: {}", e.msg));
    }
    if (!root.IsMap())
      fail(root,
           fmt::format("expected a scenario (a map with at least motion.segments or motion.knots), got {}",
                       kind_of(root)));
    sim::Scenario sc;
    sc.name = std::filesystem::path(file_).stem().string();
    sc.source = std::filesystem::path(file_).filename().string();
    bool have_motion = false;
    for_each_key(root, "", kTopKeys, [&](const std::string& key, const YAML::Node& k, const YAML::Node& v) {
      if (key == "name") {
        if (!v.IsScalar() || v.Scalar().empty() || v.Scalar().find_first_of("\r\n") != std::string::npos)
          fail(v.IsDefined() && !v.IsNull() ? v : k, "name: expected a one-line text");
        sc.name = v.Scalar();
      } else if (key == "seed") {
        sc.seed = read_uint(v, k, "seed");
      } else if (key == "step_s") {
        sc.step_s = read_double(v, k, "step_s");
      } else if (key == "robot") {
        read_robot(v, sc.robot);
      } else if (key == "motion") {
        read_motion(v, k, sc.motion);
        have_motion = true;
      } else if (key == "sensors") {
        read_sensors(v, sc.sensors);
      } else if (key == "effects") {
        read_effects(v, sc.effects);
      } else if (key == "slip_episodes") {
        read_slip_episodes(v, k, sc.slip_episodes);
      } else if (key == "terms") {
        read_terms(v, k, sc.terms);
      }
    });
    if (!have_motion)
      fail(root, "missing 'motion'; expected motion: {segments: [...]} or motion: {knots: [...]} describing "
                 "what the robot does");
    check(sc);
    return sc;
  }

 private:
  [[noreturn]] void fail(const YAML::Node& at, const std::string& msg) const {
    throw ScenarioError(file_, line_of(at), msg);
  }

  static std::string join(const std::string& path, std::string_view key) {
    return path.empty() ? std::string(key) : path + "." + std::string(key);
  }

  // Calls f(key, key_node, value_node) for each entry of map `node` (null =
  // empty map). Unknown and duplicate keys are errors; every key's line is
  // remembered under its dotted path.
  template <class F>
  void for_each_key(const YAML::Node& node, const std::string& path,
                    const std::vector<std::string_view>& allowed, F&& f) {
    if (node.IsNull()) return;
    if (!node.IsMap()) fail(node, fmt::format("{}: expected a map of key: value, got {}", path, kind_of(node)));
    std::set<std::string> seen;
    for (auto it = node.begin(); it != node.end(); ++it) {
      const YAML::Node k = it->first;
      const YAML::Node v = it->second;
      if (!k.IsScalar()) fail(k, fmt::format("{}: expected a plain key", path.empty() ? "top level" : path));
      const std::string& key = k.Scalar();
      bool ok = false;
      for (auto a : allowed) ok = ok || a == key;
      if (!ok) {
        const std::string guess = sim::closest_name(key, allowed);
        std::string valid;
        for (auto a : allowed) valid += (valid.empty() ? "" : ", ") + std::string(a);
        fail(k, fmt::format("unknown key '{}'{}{}; valid keys: {}", key, path.empty() ? "" : " in " + path,
                            guess.empty() ? "" : fmt::format(" (did you mean '{}'?)", guess), valid));
      }
      if (!seen.insert(key).second) fail(k, fmt::format("duplicate key '{}'", join(path, key)));
      lines_[join(path, key)] = line_of(k);
      f(key, k, v);
    }
  }

  const YAML::Node& value_or_key(const YAML::Node& v, const YAML::Node& k) const {
    return v.IsDefined() && !v.IsNull() ? v : k;
  }

  double read_double(const YAML::Node& v, const YAML::Node& k, const std::string& what) const {
    if (!v.IsScalar()) fail(value_or_key(v, k), fmt::format("{}: expected a number, got {}", what, kind_of(v)));
    std::string_view s = v.Scalar();
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    double x = 0.0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(x))
      fail(v, fmt::format("{}: expected a finite number, got '{}'", what, v.Scalar()));
    return x;
  }

  std::uint64_t read_uint(const YAML::Node& v, const YAML::Node& k, const std::string& what) const {
    if (!v.IsScalar())
      fail(value_or_key(v, k), fmt::format("{}: expected a non-negative integer, got {}", what, kind_of(v)));
    const std::string& s = v.Scalar();
    std::uint64_t x = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size())
      fail(v, fmt::format("{}: expected a non-negative integer, got '{}'", what, s));
    return x;
  }

  bool read_bool(const YAML::Node& v, const YAML::Node& k, const std::string& what) const {
    if (v.IsScalar()) {
      const std::string& s = v.Scalar();
      if (s == "true" || s == "True" || s == "yes" || s == "on") return true;
      if (s == "false" || s == "False" || s == "no" || s == "off") return false;
    }
    fail(value_or_key(v, k), fmt::format("{}: expected true or false, got {}", what,
                                         v.IsScalar() ? "'" + v.Scalar() + "'" : kind_of(v)));
  }

  void read_fields(const YAML::Node& node, const std::string& path, const std::vector<Field>& fields) {
    std::vector<std::string_view> keys;
    keys.reserve(fields.size());
    for (const auto& f : fields) keys.push_back(f.key);
    for_each_key(node, path, keys, [&](const std::string& key, const YAML::Node& k, const YAML::Node& v) {
      for (const auto& f : fields) {
        if (f.key != key) continue;
        if (auto* d = std::get_if<double*>(&f.target)) **d = read_double(v, k, join(path, key));
        if (auto* b = std::get_if<bool*>(&f.target)) **b = read_bool(v, k, join(path, key));
      }
    });
  }

  void read_robot(const YAML::Node& n, sim::RobotParams& r) {
    read_fields(n, "robot",
                {{"wheel_radius_left_m", &r.wheel_radius_left_m},
                 {"wheel_radius_right_m", &r.wheel_radius_right_m},
                 {"wheel_base_m", &r.wheel_base_m},
                 {"ticks_per_rev", &r.ticks_per_rev},
                 {"mass_kg", &r.mass_kg},
                 {"yaw_inertia_kg_m2", &r.yaw_inertia_kg_m2},
                 {"wheel_inertia_kg_m2", &r.wheel_inertia_kg_m2},
                 {"viscous_friction_nm_s", &r.viscous_friction_nm_s},
                 {"coulomb_friction_nm", &r.coulomb_friction_nm},
                 {"coulomb_smoothing_rad_s", &r.coulomb_smoothing_rad_s},
                 {"torque_constant_nm_per_a", &r.torque_constant_nm_per_a},
                 {"coil_resistance_ohm", &r.coil_resistance_ohm}});
  }

  void read_sensors(const YAML::Node& n, sim::SensorParams& s) {
    for_each_key(n, "sensors", {"encoders", "commands", "gyro", "power", "ext_velocity", "aps", "ground_truth"},
                 [&](const std::string& key, const YAML::Node&, const YAML::Node& v) {
                   const std::string p = "sensors." + key;
                   if (key == "encoders")
                     read_fields(v, p,
                                 {{"enabled", &s.encoders.enabled},
                                  {"rate_hz", &s.encoders.rate_hz},
                                  {"omega", &s.encoders.omega},
                                  {"omega_resolution_rad_s", &s.encoders.omega_resolution_rad_s}});
                   else if (key == "commands")
                     read_fields(v, p,
                                 {{"enabled", &s.commands.enabled},
                                  {"rate_hz", &s.commands.rate_hz},
                                  {"resolution", &s.commands.resolution}});
                   else if (key == "gyro")
                     read_fields(v, p,
                                 {{"enabled", &s.gyro.enabled},
                                  {"rate_hz", &s.gyro.rate_hz},
                                  {"sigma_rad_s", &s.gyro.sigma_rad_s},
                                  {"resolution_rad_s", &s.gyro.resolution_rad_s}});
                   else if (key == "power")
                     read_fields(v, p,
                                 {{"enabled", &s.power.enabled},
                                  {"rate_hz", &s.power.rate_hz},
                                  {"sigma_w", &s.power.sigma_w},
                                  {"resolution_w", &s.power.resolution_w}});
                   else if (key == "ext_velocity")
                     read_fields(v, p,
                                 {{"enabled", &s.ext_velocity.enabled},
                                  {"rate_hz", &s.ext_velocity.rate_hz},
                                  {"sigma_v_m_s", &s.ext_velocity.sigma_v_m_s},
                                  {"sigma_w_rad_s", &s.ext_velocity.sigma_w_rad_s},
                                  {"resolution", &s.ext_velocity.resolution}});
                   else if (key == "aps")
                     read_fields(v, p,
                                 {{"enabled", &s.aps.enabled},
                                  {"rate_hz", &s.aps.rate_hz},
                                  {"sigma_m", &s.aps.sigma_m},
                                  {"resolution_m", &s.aps.resolution_m}});
                   else if (key == "ground_truth")
                     read_fields(v, p,
                                 {{"enabled", &s.ground_truth.enabled},
                                  {"rate_hz", &s.ground_truth.rate_hz},
                                  {"sigma_m", &s.ground_truth.sigma_m},
                                  {"sigma_rad", &s.ground_truth.sigma_rad},
                                  {"resolution_m", &s.ground_truth.resolution_m},
                                  {"resolution_rad", &s.ground_truth.resolution_rad}});
                 });
  }

  void read_motion(const YAML::Node& n, const YAML::Node& key, sim::MotionParams& m) {
    if (!n.IsMap())
      fail(value_or_key(n, key),
           fmt::format("motion: expected a map with segments or knots, got {}", kind_of(n)));
    bool have_segments = false, have_knots = false;
    YAML::Node knots_key;
    for_each_key(n, "motion", {"start", "max_accel_m_s2", "max_angular_accel_rad_s2", "segments", "knots"},
                 [&](const std::string& k, const YAML::Node& kn, const YAML::Node& v) {
                   if (k == "start")
                     read_fields(
                         v, "motion.start",
                         {{"x_m", &m.start_x_m}, {"y_m", &m.start_y_m}, {"theta_rad", &m.start_theta_rad}});
                   if (k == "max_accel_m_s2") m.max_accel_m_s2 = read_double(v, kn, "motion." + k);
                   if (k == "max_angular_accel_rad_s2")
                     m.max_angular_accel_rad_s2 = read_double(v, kn, "motion." + k);
                   if (k == "segments") {
                     read_segments(v, kn, "motion.segments", m.segments);
                     have_segments = true;
                   }
                   if (k == "knots") {
                     read_knots(v, kn, m.knots);
                     knots_key.reset(kn);
                     have_knots = true;
                   }
                 });
    if (have_segments && have_knots)
      fail(knots_key, "motion: segments and knots both given; expected one of them (segments: planned "
                      "motion, knots: an explicit velocity profile)");
    if (have_knots) {
      if (m.knots.empty())
        fail(knots_key,
             "motion.knots: no knots; expected knots: [[t_s, v_m_s, w_rad_s], ...] starting at t_s = 0");
      return;
    }
    if (!have_segments || m.segments.empty())
      fail(value_or_key(n, key), "motion: no segments or knots; expected segments: [- straight: {...}, ...] "
                                 "or knots: [[t_s, v_m_s, w_rad_s], ...]");
  }

  // motion.knots: a list of [t_s, v_m_s, w_rad_s] triples. Their order and
  // values are checked by MotionProfile (in check()), at the knot's line.
  void read_knots(const YAML::Node& n, const YAML::Node& key, std::vector<sim::VelocityKnot>& out) {
    if (!n.IsSequence())
      fail(value_or_key(n, key), fmt::format("motion.knots: expected a list of [t_s, v_m_s, w_rad_s] "
                                             "triples, got {}",
                                             kind_of(n)));
    if (n.size() > kMaxKnots)
      fail(key, fmt::format("motion.knots: {} knots; expected at most {}", n.size(), kMaxKnots));
    out.reserve(n.size());
    knot_lines_.reserve(n.size());
    for (std::size_t i = 0; i < n.size(); ++i) {
      const YAML::Node item = n[i];
      const std::string ip = fmt::format("motion.knots[{}]", i + 1);
      if (!item.IsSequence() || item.size() != 3)
        fail(value_or_key(item, key),
             fmt::format("{}: expected a list [t_s, v_m_s, w_rad_s] of 3 numbers, got {}", ip,
                         item.IsSequence() ? fmt::format("{} items", item.size()) : kind_of(item)));
      sim::VelocityKnot k;
      k.t_s = read_double(item[0], item, ip + ".t_s");
      k.v_m_s = read_double(item[1], item, ip + ".v_m_s");
      k.w_rad_s = read_double(item[2], item, ip + ".w_rad_s");
      out.push_back(k);
      knot_lines_.push_back(line_of(item));
    }
  }

  void read_segments(const YAML::Node& n, const YAML::Node& key, const std::string& path,
                     std::vector<sim::Segment>& out) {
    if (!n.IsSequence())
      fail(value_or_key(n, key), fmt::format("{}: expected a list of segments, got {}", path, kind_of(n)));
    for (std::size_t i = 0; i < n.size(); ++i) {
      const YAML::Node item = n[i];
      const std::string ip = fmt::format("{}[{}]", path, i + 1);
      if (!item.IsMap() || item.size() != 1)
        fail(item, fmt::format("{}: expected a one-key map such as '- straight: {{distance_m: 2, "
                               "speed_m_s: 0.5}}' (kinds: straight, arc, spin, stop, repeat), got {}",
                               ip, item.IsMap() ? fmt::format("{} keys", item.size()) : kind_of(item)));
      for_each_key(
          item, ip, {"straight", "arc", "spin", "stop", "repeat"},
          [&](const std::string& kind, const YAML::Node& kn, const YAML::Node& v) {
            if (kind == "repeat") {
              read_repeat(v, kn, ip + ".repeat", out);
              return;
            }
            sim::Segment s;
            s.line = static_cast<int>(line_of(kn));
            const std::string sp = fmt::format("{}.{}", ip, kind);
            if (!v.IsMap())
              fail(value_or_key(v, kn),
                   fmt::format("{}: expected a map of parameters, got {}", sp, kind_of(v)));
            std::vector<Field> fields;
            if (kind == "straight") {
              s.kind = sim::Segment::Kind::straight;
              fields = {{"distance_m", &s.distance_m}, {"speed_m_s", &s.speed_m_s}};
            } else if (kind == "arc") {
              s.kind = sim::Segment::Kind::arc;
              fields = {{"radius_m", &s.radius_m}, {"angle_deg", &s.angle_deg}, {"speed_m_s", &s.speed_m_s}};
            } else if (kind == "spin") {
              s.kind = sim::Segment::Kind::spin;
              fields = {{"angle_deg", &s.angle_deg}, {"rate_deg_s", &s.rate_deg_s}};
            } else {
              s.kind = sim::Segment::Kind::stop;
              fields = {{"duration_s", &s.duration_s}};
            }
            read_fields(v, sp, fields);
            for (const auto& f : fields)
              if (!v[std::string(f.key)])
                fail(kn, fmt::format("{}: missing '{}'; {} needs {}", sp, f.key, kind, field_list(fields)));
            try {
              (void)sim::segment_cruise(s, out.size());
            } catch (const sim::ProfileError& e) {
              fail(kn, fmt::format("{}: {}", sp, strip_segment_prefix(e.what())));
            }
            if (out.size() >= kMaxSegments)
              fail(kn, fmt::format("more than {} segments after expanding repeats", kMaxSegments));
            out.push_back(s);
          });
    }
  }

  void read_repeat(const YAML::Node& v, const YAML::Node& kn, const std::string& path,
                   std::vector<sim::Segment>& out) {
    long count = -1;
    YAML::Node body, body_key;
    bool have_body = false;
    for_each_key(v, path, {"count", "segments"},
                 [&](const std::string& k, const YAML::Node& kk, const YAML::Node& vv) {
                   if (k == "count") {
                     const double c = read_double(vv, kk, path + ".count");
                     if (!(c >= 1 && c <= static_cast<double>(kMaxRepeat) && c == std::floor(c)))
                       fail(vv, fmt::format("{}.count = {}; expected a whole number in [1, {}]", path,
                                            vv.Scalar(), kMaxRepeat));
                     count = static_cast<long>(c);
                   } else {
                     body.reset(vv);
                     body_key.reset(kk);
                     have_body = true;
                   }
                 });
    if (count < 0 || !have_body) fail(kn, fmt::format("{}: expected {{count: N, segments: [...]}}", path));
    std::vector<sim::Segment> once;
    read_segments(body, body_key, path + ".segments", once);
    if (once.empty()) fail(body_key, fmt::format("{}.segments: expected at least one segment", path));
    if (out.size() + once.size() * static_cast<std::size_t>(count) > kMaxSegments)
      fail(kn, fmt::format("{}: more than {} segments after expanding repeats", path, kMaxSegments));
    for (long r = 0; r < count; ++r) out.insert(out.end(), once.begin(), once.end());
  }

  static std::string field_list(const std::vector<Field>& fields) {
    std::string s;
    for (const auto& f : fields) s += (s.empty() ? "" : ", ") + std::string(f.key);
    return s;
  }

  // "segment 3 (arc): radius_m = ..." -> "radius_m = ..." (the path says which).
  static std::string strip_segment_prefix(const std::string& what) {
    const auto p = what.find("): ");
    return what.rfind("segment ", 0) == 0 && p != std::string::npos ? what.substr(p + 3) : what;
  }

  void read_effects(const YAML::Node& n, sim::Effects& fx) {
    if (n.IsNull()) return;
    if (!n.IsMap())
      fail(n, fmt::format("effects: expected a map of effect: {{param: value}}, got {}", kind_of(n)));
    std::vector<std::string_view> names;
    for (const auto& e : sim::effect_table()) names.push_back(e.name);
    for_each_key(n, "effects", names, [&](const std::string& name, const YAML::Node& kn, const YAML::Node& v) {
      const sim::EffectInfo& info = *sim::find_effect(name);
      std::vector<std::string_view> params;
      for (const auto& p : info.params) params.push_back(p.name);
      sim::EffectSpec spec{name, {}};
      const std::string path = "effects." + name;
      for_each_key(v, path, params, [&](const std::string& param, const YAML::Node& pk, const YAML::Node& pv) {
        const double x = read_double(pv, pk, path + "." + param);
        std::string why;
        if (!sim::check_param(info, *sim::find_param(info, param), x, &why)) fail(pv, why);
        spec.values.emplace_back(param, x);
      });
      try {
        sim::apply_effect(fx, spec);
      } catch (const std::invalid_argument& e) {
        fail(kn, e.what());
      }
    });
  }

  // One of `choices` (e.g. kind: spin|hold), suggesting the closest on a typo.
  std::string read_choice(const YAML::Node& v, const YAML::Node& k, const std::string& what,
                          const std::vector<std::string_view>& choices) const {
    std::string valid;
    for (auto c : choices) valid += (valid.empty() ? "" : " or ") + std::string(c);
    if (!v.IsScalar())
      fail(value_or_key(v, k), fmt::format("{}: expected {}, got {}", what, valid, kind_of(v)));
    for (auto c : choices)
      if (v.Scalar() == c) return v.Scalar();
    const std::string guess = sim::closest_name(v.Scalar(), choices);
    fail(v, fmt::format("{} = '{}'{}; expected {}", what, v.Scalar(),
                        guess.empty() ? "" : fmt::format(" (did you mean '{}'?)", guess), valid));
  }

  // slip_episodes: a list of {kind, wheel, t0_s, t1_s, s[, ramp_s][, brake_nm]}
  // maps. Each episode's fields are checked here (at the bad field's line);
  // overlaps on one wheel by validate_scenario in check().
  void read_slip_episodes(const YAML::Node& n, const YAML::Node& key, std::vector<sim::SlipEpisode>& out) {
    if (n.IsNull()) return;
    if (!n.IsSequence())
      fail(value_or_key(n, key), fmt::format("slip_episodes: expected a list of {{kind: spin|hold, wheel: "
                                             "left|right, t0_s, t1_s, s, ramp_s, brake_nm}} maps, got {}",
                                             kind_of(n)));
    if (n.size() > sim::kMaxSlipEpisodes)
      fail(key,
           fmt::format("slip_episodes: {} episodes; expected at most {}", n.size(), sim::kMaxSlipEpisodes));
    for (std::size_t i = 0; i < n.size(); ++i) {
      const YAML::Node item = n[i];
      const std::string ip = fmt::format("slip_episodes[{}]", i + 1);
      if (!item.IsMap())
        fail(value_or_key(item, key), fmt::format("{}: expected a map such as {{kind: spin, wheel: left, t0_s: "
                                                  "40, t1_s: 44, s: 0.6}}, got {}",
                                                  ip, kind_of(item)));
      sim::SlipEpisode e;
      e.line = static_cast<int>(line_of(item));
      lines_[ip] = line_of(item);
      std::map<std::string, YAML::Node> at;  // field -> its value's node, for messages
      for_each_key(item, ip, {"kind", "wheel", "t0_s", "t1_s", "s", "ramp_s", "brake_nm"},
                   [&](const std::string& f, const YAML::Node& k, const YAML::Node& v) {
                     at[f].reset(value_or_key(v, k));
                     const std::string what = fmt::format("{}.{}", ip, f);
                     if (f == "kind")
                       e.kind = read_choice(v, k, what, {"spin", "hold"}) == "spin"
                                    ? sim::SlipEpisode::Kind::spin
                                    : sim::SlipEpisode::Kind::hold;
                     else if (f == "wheel")
                       e.wheel = read_choice(v, k, what, {"left", "right"}) == "left"
                                     ? sim::SlipEpisode::Wheel::left
                                     : sim::SlipEpisode::Wheel::right;
                     else if (f == "t0_s")
                       e.t0_s = read_double(v, k, what);
                     else if (f == "t1_s")
                       e.t1_s = read_double(v, k, what);
                     else if (f == "s")
                       e.s = read_double(v, k, what);
                     else if (f == "ramp_s")
                       e.ramp_s = read_double(v, k, what);
                     else
                       e.brake_nm = read_double(v, k, what);
                   });
      for (const char* required : {"kind", "wheel", "t0_s", "t1_s", "s"})
        if (!at.count(required))
          fail(item, fmt::format("{}: missing '{}'; an episode needs kind, wheel, t0_s, t1_s and s (ramp_s, "
                                 "brake_nm optional)",
                                 ip, required));
      std::string field, why;
      if (!sim::check_slip_episode(e, &field, &why))
        fail(at.count(field) ? at[field] : item, fmt::format("{}.{}", ip, why));
      out.push_back(e);
    }
  }

  // terms: a list of {target: v_l|v_r, term: NAME, coef: NUMBER} maps
  // (odotune/sim/model_terms.h; NAME in either form, e.g. "v_l*sin(phi_l)").
  void read_terms(const YAML::Node& n, const YAML::Node& key, std::vector<sim::ModelTerm>& out) {
    if (n.IsNull()) return;
    const std::string form = "{target: v_l|v_r, term: NAME, coef: NUMBER} maps";
    if (!n.IsSequence())
      fail(value_or_key(n, key), fmt::format("terms: expected a list of {}, got {}", form, kind_of(n)));
    for (std::size_t i = 0; i < n.size(); ++i) {
      const std::string ip = fmt::format("terms[{}]", i + 1);
      std::map<std::string, YAML::Node> at;
      if (!n[i].IsMap())
        fail(value_or_key(n[i], key),
             fmt::format("{}: expected one of the {}, got {}", ip, form, kind_of(n[i])));
      for_each_key(n[i], ip, {"target", "term", "coef"},
                   [&](const std::string& f, const YAML::Node& k, const YAML::Node& v) {
                     at[f].reset(value_or_key(v, k));
                   });
      for (const char* required : {"target", "term", "coef"})
        if (!at.count(required))
          fail(n[i], fmt::format("{}: missing '{}'; a term needs target, term and coef", ip, required));
      sim::ModelTerm m;
      const char* field = "target";
      try {
        m.target = sim::parse_target(at["target"].IsScalar() ? at["target"].Scalar() : "");
        field = "term";
        m.basis = sim::parse_basis(m.target, at["term"].IsScalar() ? at["term"].Scalar() : "");
      } catch (const std::invalid_argument& e) {
        fail(at[field], fmt::format("{}.{}: {}", ip, field, e.what()));
      }
      m.coef = read_double(at["coef"], at["coef"], ip + ".coef");
      out.push_back(m);
      std::string why;
      if (!sim::validate_terms(out, &why)) fail(n[i], "terms: " + why);
    }
  }

  // Whole-scenario checks, reported at the line of the offending key.
  void check(const sim::Scenario& sc) const {
    try {
      (void)sim::MotionProfile(sc.motion);
    } catch (const sim::ProfileError& e) {
      const std::string what = e.what();
      std::size_t line = line_for("motion." + what.substr(0, what.find(' ')));  // e.g. max_accel_m_s2
      if (e.segment() < sc.motion.segments.size() && sc.motion.segments[e.segment()].line > 0)
        line = static_cast<std::size_t>(sc.motion.segments[e.segment()].line);
      if (sc.motion.segments.empty() && e.segment() < knot_lines_.size() && knot_lines_[e.segment()] > 0)
        line = knot_lines_[e.segment()];
      throw ScenarioError(file_, line, fmt::format("motion: {}", e.what()));
    }
    std::string why;
    if (!sim::validate_scenario(sc, &why)) {
      const auto end = why.find_first_of(" :");
      throw ScenarioError(file_, line_for(why.substr(0, end)), why);
    }
  }

  // Line of the longest recorded prefix of a dotted path (0 if none).
  std::size_t line_for(std::string path) const {
    while (!path.empty()) {
      if (auto it = lines_.find(path); it != lines_.end()) return it->second;
      const auto dot = path.rfind('.');
      if (dot == std::string::npos) break;
      path.resize(dot);
    }
    return 0;
  }

  std::string file_;
  std::map<std::string, std::size_t> lines_;
  std::vector<std::size_t> knot_lines_;  // line of each motion.knots entry
};

}  // namespace

ScenarioError::ScenarioError(std::string file, std::size_t line, const std::string& reason)
    : std::runtime_error(line > 0 ? fmt::format("{}:{}: {}", file, line, reason)
                                  : fmt::format("{}: {}", file, reason)),
      file_(std::move(file)),
      line_(line) {}

sim::Scenario parse_scenario(std::string_view yaml_text, const std::string& filename) {
  return Parser(filename).parse(yaml_text);
}

sim::Scenario load_scenario(const std::filesystem::path& file) {
  namespace fs = std::filesystem;
  const std::string name = file.string();
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw ScenarioError(name, 0,
                        fs::exists(file, ec) ? "not a regular file; expected a scenario YAML file"
                                             : "no such file; expected a scenario YAML file");
  const auto size = fs::file_size(file, ec);
  if (ec || size > kMaxFileBytes)
    throw ScenarioError(name, 0,
                        fmt::format("cannot use this file ({}); expected a scenario of at most {} bytes",
                                    ec ? ec.message() : fmt::format("{} bytes", size), kMaxFileBytes));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ScenarioError(name, 0, "cannot open the file for reading");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ScenarioError(name, 0, "error while reading the file");
  return parse_scenario(text.str(), name);
}

}  // namespace odotune::formats

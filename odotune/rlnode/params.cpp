// Reads and rewrites robot_localization parameter files (odotune/rlnode/params.h).
// Key names, types and defaults: robot_localization's src/ros_filter.cpp
// loadParams() and src/navsat_transform.cpp, ROS 1 (noetic-devel) and ROS 2,
// read for behaviour. A ROS 2 node declares its parameters with a type and
// refuses a file whose value has another: an integer literal for a double
// parameter (`frequency: 30`) stops the node, so it is refused here too.
#include <odotune/rlnode/params.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

namespace odotune::rlnode {

Matrix15 default_process_noise() {
  Vector15 d;
  d << 0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015;
  return d.asDiagonal();
}

Matrix15 default_initial_estimate_covariance() { return Matrix15::Identity() * 1e-9; }

std::string_view to_string(KeyUse u) {
  switch (u) {
    case KeyUse::reproduced: return "reproduced";
    case KeyUse::no_effect: return "no effect";
    case KeyUse::not_read: return "not read";
  }
  return "";
}

std::string_view to_string(SensorKind k) {
  switch (k) {
    case SensorKind::odom: return "odom";
    case SensorKind::imu: return "imu";
    case SensorKind::pose: return "pose";
    case SensorKind::twist: return "twist";
  }
  return "";
}

namespace {

namespace fs = std::filesystem;

// The type the node gives a key's value.
enum class Kind : std::uint8_t { boolean, number, integer, text, numbers, booleans, any };

// A key that is reproduced only while another feature is on (use_control,
// smooth_lagged_data), and changes nothing otherwise.
enum class Needs : std::uint8_t { nothing, control, smoothing };

struct Known {
  std::string_view name;
  Kind kind;
  KeyUse use = KeyUse::reproduced;  // what the replay makes of it (RlParams::keys)
  Needs needs = Needs::nothing;
};

// ekf_node's keys besides the inputs' (odomN…).
constexpr Known kEkfKeys[] = {
    // read: they shape the estimate
    {"frequency", Kind::number},
    {"sensor_timeout", Kind::number},
    {"two_d_mode", Kind::boolean},
    {"predict_to_current_time", Kind::boolean},
    {"dynamic_process_noise_covariance", Kind::boolean},
    {"gravitational_acceleration", Kind::number},
    {"map_frame", Kind::text},
    {"odom_frame", Kind::text},
    {"base_link_frame", Kind::text},
    {"world_frame", Kind::text},
    {"process_noise_covariance", Kind::numbers},
    {"initial_estimate_covariance", Kind::numbers},
    {"initial_state", Kind::numbers},
    // ukf_node's only (a section with them is the UKF's)
    {"alpha", Kind::number},
    {"kappa", Kind::number},
    {"beta", Kind::number},
    // use_control and its keys (read_control; while use_control is false
    // they have no effect)
    {"use_control", Kind::boolean},
    {"control_timeout", Kind::number, KeyUse::reproduced, Needs::control},
    {"stamped_control", Kind::boolean, KeyUse::reproduced, Needs::control},
    {"control_config", Kind::any, KeyUse::reproduced, Needs::control},
    {"acceleration_limits", Kind::any, KeyUse::reproduced, Needs::control},
    {"acceleration_gains", Kind::any, KeyUse::reproduced, Needs::control},
    {"deceleration_limits", Kind::any, KeyUse::reproduced, Needs::control},
    {"deceleration_gains", Kind::any, KeyUse::reproduced, Needs::control},
    // smooth_lagged_data and its history_length
    {"smooth_lagged_data", Kind::boolean},
    {"history_length", Kind::number, KeyUse::reproduced, Needs::smoothing},
    // refused unless false (refusal_reason), filter_type unless "ekf"
    {"disabled_at_startup", Kind::boolean},
    {"filter_type", Kind::text},
    // no effect on the estimate (reset_on_time_jump: a bag played once, as
    // `rosbag play --clock` plays it, never moves the clock back)
    {"reset_on_time_jump", Kind::boolean, KeyUse::no_effect},
    {"use_sim_time", Kind::boolean, KeyUse::no_effect},
    {"clear_params", Kind::boolean, KeyUse::no_effect},
    {"publish_tf", Kind::boolean, KeyUse::no_effect},
    {"publish_acceleration", Kind::boolean, KeyUse::no_effect},
    {"permit_corrected_publication", Kind::boolean, KeyUse::no_effect},
    {"print_diagnostics", Kind::boolean, KeyUse::no_effect},
    {"debug", Kind::boolean, KeyUse::no_effect},
    {"debug_out_file", Kind::text, KeyUse::no_effect},
    {"transform_time_offset", Kind::number, KeyUse::no_effect},
    {"transform_timeout", Kind::number, KeyUse::no_effect},
    {"tf_prefix", Kind::any, KeyUse::no_effect},
    {"base_link_frame_output", Kind::text, KeyUse::no_effect},
    {"invert_tf", Kind::boolean, KeyUse::no_effect},
};

// navsat_transform_node's keys; `datum` is checked when read.
constexpr Known kNavsatKeys[] = {
    {"frequency", Kind::number},
    {"delay", Kind::number},
    {"magnetic_declination_radians", Kind::number},
    {"yaw_offset", Kind::number},
    {"zero_altitude", Kind::boolean},
    {"use_local_cartesian", Kind::boolean},
    {"use_odometry_yaw", Kind::boolean},
    {"wait_for_datum", Kind::boolean},
    {"datum", Kind::numbers},
    {"publish_filtered_gps", Kind::boolean, KeyUse::no_effect},
    {"broadcast_cartesian_transform", Kind::boolean, KeyUse::no_effect},
    {"broadcast_utm_transform", Kind::boolean, KeyUse::no_effect},
    {"broadcast_cartesian_transform_as_parent_frame", Kind::boolean, KeyUse::no_effect},
    {"broadcast_utm_transform_as_parent_frame", Kind::boolean, KeyUse::no_effect},
    {"broadcast_utm_transform_as_parent_frame_", Kind::boolean,
     KeyUse::no_effect},  // ROS 2 declares it with the underscore
    {"cartesian_frame_id", Kind::text, KeyUse::no_effect},
    {"transform_timeout", Kind::number, KeyUse::no_effect},
    {"use_sim_time", Kind::boolean, KeyUse::no_effect},
    {"clear_params", Kind::boolean, KeyUse::no_effect},
    {"tf_prefix", Kind::any, KeyUse::no_effect},
};
// navsat keys ekf_node has too: they do not make a section navsat_transform's.
constexpr std::string_view kSharedKeys[] = {"frequency", "transform_timeout", "use_sim_time", "clear_params",
                                            "tf_prefix"};

constexpr std::uint8_t bit(SensorKind k) { return static_cast<std::uint8_t>(1U << static_cast<unsigned>(k)); }
constexpr std::uint8_t kOdom = bit(SensorKind::odom), kImu = bit(SensorKind::imu),
                       kPose = bit(SensorKind::pose), kTwist = bit(SensorKind::twist),
                       kAll = kOdom | kImu | kPose | kTwist;

// The keys of input odomN (poseN, twistN, imuN): "odomN" + suffix, for the kinds in `kinds`.
struct InputRule {
  std::string_view suffix;
  Kind kind;
  std::uint8_t kinds;
  KeyUse use = KeyUse::reproduced;
};
constexpr InputRule kInputKeys[] = {
    {"", Kind::text, kAll},
    {"_config", Kind::booleans, kAll},
    {"_queue_size", Kind::integer, kAll, KeyUse::no_effect},
    {"_nodelay", Kind::boolean, kAll, KeyUse::no_effect},
    {"_differential", Kind::boolean, kOdom | kPose | kImu},
    {"_relative", Kind::boolean, kOdom | kPose | kImu},
    {"_pose_use_child_frame", Kind::boolean, kOdom},
    {"_pose_rejection_threshold", Kind::number, kOdom | kImu},
    {"_twist_rejection_threshold", Kind::number, kOdom | kImu},
    {"_rejection_threshold", Kind::number, kPose | kTwist},
    {"_linear_acceleration_rejection_threshold", Kind::number, kImu},
    {"_remove_gravitational_acceleration", Kind::boolean, kImu},
};
constexpr SensorKind kNodeOrder[] = {SensorKind::odom, SensorKind::pose, SensorKind::twist, SensorKind::imu};

template <std::size_t N>
const Known* find_known(const Known (&table)[N], std::string_view name) {
  for (const Known& k : table)
    if (k.name == name) return &k;
  return nullptr;
}

struct InputKey {
  SensorKind kind = SensorKind::odom;
  int index = 0;
  const InputRule* rule = nullptr;  // null: no such key for this kind
};

// "odom12_config" -> odom, 12, the _config rule; nullopt when the key is not odomN… at all.
std::optional<InputKey> split_input_key(std::string_view key) {
  for (const SensorKind k : kNodeOrder) {
    const std::string_view prefix = to_string(k);
    if (!key.starts_with(prefix)) continue;
    std::size_t end = prefix.size();
    while (end < key.size() && end < prefix.size() + 7 && key[end] >= '0' && key[end] <= '9') ++end;
    const std::string_view digits = key.substr(prefix.size(), end - prefix.size());
    if (digits.empty() || (digits.size() > 1 && digits[0] == '0')) return std::nullopt;
    InputKey in{k, std::stoi(std::string(digits)), nullptr};
    for (const InputRule& r : kInputKeys)
      if (r.suffix == key.substr(end) && (r.kinds & bit(k)) != 0) in.rule = &r;
    return in;
  }
  return std::nullopt;
}

Kind ekf_kind(std::string_view key) {
  if (const Known* k = find_known(kEkfKeys, key)) return k->kind;
  const auto in = split_input_key(key);
  return in && in->rule ? in->rule->kind : Kind::any;
}

Kind navsat_kind(std::string_view key) {
  const Known* k = find_known(kNavsatKeys, key);
  return k ? k->kind : Kind::any;
}

// Why a key's value is refused (the replay does not reproduce it); empty when it is not.
std::string_view refusal_reason(std::string_view key) {
  if (key == "disabled_at_startup") return "ekf_node would wait for its enable service";
  return "";
}

bool is_integer_literal(std::string_view s) {
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) s.remove_prefix(1);
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::string describe(const YAML::Node& v) {
  switch (v.Type()) {
    case YAML::NodeType::Scalar:
      return v.Tag() == "!" ? fmt::format("the quoted string \"{}\"", v.Scalar())
                            : fmt::format("'{}'", v.Scalar());
    case YAML::NodeType::Sequence: return fmt::format("a list of {}", v.size());
    case YAML::NodeType::Map: return "a mapping";
    default: return "nothing";
  }
}

// Reads values, throwing "FILE:LINE: …" at the offending node.
struct Reader {
  const fs::path& file;
  bool ros2 = false;
  // Where note() writes (nullptr: nowhere), for what the reader leaves out.
  std::vector<std::string>* notes = nullptr;

  void note(const YAML::Node& at, const std::string& what) const {
    if (!notes) return;
    const YAML::Mark m = at.Mark();
    notes->push_back(fmt::format("{}:{}: {}", file.string(), m.is_null() ? 1 : m.line + 1, what));
  }

  [[noreturn]] void fail(const YAML::Node& at, const std::string& what) const {
    const YAML::Mark m = at.Mark();
    throw std::invalid_argument(fmt::format("{}:{}: {}", file.string(), m.is_null() ? 1 : m.line + 1, what));
  }
  bool boolean(const std::string& key, const YAML::Node& v) const {
    bool b = false;
    if (v.Tag() == "!" || !YAML::convert<bool>::decode(v, b))
      fail(v, fmt::format("{} must be true or false, got {}", key, describe(v)));
    return b;
  }
  double number(const std::string& key, const YAML::Node& v) const {
    double d = 0.0;
    if (!v.IsScalar() || v.Tag() == "!" || !YAML::convert<double>::decode(v, d) || std::isnan(d))
      fail(v, fmt::format("{} must be a number, got {}", key, describe(v)));
    if (ros2 && is_integer_literal(v.Scalar())) {
      fail(v, fmt::format("{} is the integer {}, which ROS 2 refuses for a double parameter, expected {}.0",
                          key, v.Scalar(), v.Scalar()));
    }
    return d;
  }
  void integer(const std::string& key, const YAML::Node& v) const {
    if (!v.IsScalar() || v.Tag() == "!" || !is_integer_literal(v.Scalar()))
      fail(v, fmt::format("{} must be an integer, got {}", key, describe(v)));
  }
  std::string text(const std::string& key, const YAML::Node& v) const {
    if (!v.IsScalar()) fail(v, fmt::format("{} must be a string, got {}", key, describe(v)));
    return v.Scalar();
  }
  void list(const std::string& key, const YAML::Node& v, std::string_view of) const {
    if (!v.IsSequence()) fail(v, fmt::format("{} must be a list of {}, got {}", key, of, describe(v)));
  }
  std::vector<double> numbers(const std::string& key, const YAML::Node& v) const {
    list(key, v, "numbers");
    std::vector<double> out;
    for (std::size_t i = 0; i < v.size(); ++i)
      out.push_back(number(fmt::format("{} entry {}", key, i + 1), v[i]));
    return out;
  }
  std::vector<bool> booleans(const std::string& key, const YAML::Node& v) const {
    list(key, v, "booleans");
    std::vector<bool> out;
    for (std::size_t i = 0; i < v.size(); ++i)
      out.push_back(boolean(fmt::format("{} entry {}", key, i + 1), v[i]));
    return out;
  }
  void check(const std::string& key, const YAML::Node& v, Kind kind) const {
    switch (kind) {
      case Kind::boolean: boolean(key, v); break;
      case Kind::number: number(key, v); break;
      case Kind::integer: integer(key, v); break;
      case Kind::text: text(key, v); break;
      case Kind::numbers: numbers(key, v); break;
      case Kind::booleans: booleans(key, v); break;
      case Kind::any: break;
    }
  }
};

struct Entry {
  YAML::Node key, value;
};

// A section's parameters in file order, each name once.
struct Keys {
  std::vector<std::pair<std::string, Entry>> order;
  std::map<std::string, std::size_t> index;

  const Entry* find(const std::string& name) const {
    const auto it = index.find(name);
    return it == index.end() ? nullptr : &order[it->second].second;
  }
};

Keys collect(const Reader& r, const YAML::Node& map) {
  Keys keys;
  for (const auto& kv : map) {
    if (!kv.first.IsScalar())
      r.fail(kv.first, fmt::format("a parameter name must be a string, got {}", describe(kv.first)));
    const std::string& name = kv.first.Scalar();
    if (const Entry* first = keys.find(name)) {
      // Both values the same: whichever the node takes, it is that value.
      if (YAML::Dump(first->value) == YAML::Dump(kv.second)) {
        r.note(kv.first, fmt::format("{} is given twice with the same value (first at line {}); read once",
                                     name, first->key.Mark().line + 1));
        continue;
      }
      r.fail(kv.first,
             fmt::format("{} is given twice with different values ({} at line {}, {} here), expected "
                         "each parameter once",
                         name, YAML::Dump(first->value), first->key.Mark().line + 1, YAML::Dump(kv.second)));
    }
    keys.index[name] = keys.order.size();
    keys.order.push_back({name, Entry{kv.first, kv.second}});
  }
  return keys;
}

void refuse_if_true(const Reader& r, const std::string& key, const Entry& e) {
  const std::string_view why = refusal_reason(key);
  if (why.empty() || !r.boolean(key, e.value)) return;
  r.fail(e.key,
         fmt::format("{}: {} is not reproduced by odotune's replay ({}), expected false or the key left out",
                     key, e.value.Scalar(), why));
}

// Type-checks one key of the EKF section; refuses unknown keys, inputs the
// node never reads (past the first gap of their numbering) and refused values.
void check_ekf_key(const Reader& r, const std::string& name, const Entry& e, const std::array<int, 4>& count,
                   const std::string& section) {
  if (const Known* k = find_known(kEkfKeys, name)) {
    r.check(name, e.value, k->kind);
    refuse_if_true(r, name, e);
    if (name == "filter_type" && r.text(name, e.value) != "ekf") {
      r.fail(e.key,
             fmt::format("filter_type: {} is not reproduced by odotune's replay of ekf_node, expected ekf",
                         e.value.Scalar()));
    }
    return;
  }
  const auto in = split_input_key(name);
  if (!in || !in->rule) {
    r.note(e.key, fmt::format("'{}' of {} is not one of robot_localization's parameters, which does not read "
                              "it either (left out; check its spelling)",
                              name, section));
    return;
  }
  const int n = count[static_cast<std::size_t>(in->kind)];
  if (in->index >= n) {
    const std::string_view k = to_string(in->kind);
    r.note(e.key, fmt::format("{} is not read by robot_localization either: it reads {}0, {}1, ... up to the "
                              "first missing number, and {}{} is missing (left out)",
                              name, k, k, k, n));
    return;
  }
  r.check(name, e.value, in->rule->kind);
  refuse_if_true(r, name, e);
}

// What the replay makes of one key of the filter's section (after read_ekf,
// read_control and read_smoothing; refused keys never get here).
KeyUse ekf_key_use(const std::string& name, const std::array<int, 4>& count, const RlParams& p, bool ros2) {
  const Known* k = find_known(kEkfKeys, name);
  if (!k) {
    const auto in = split_input_key(name);
    if (!in || !in->rule || in->index >= count[static_cast<std::size_t>(in->kind)]) return KeyUse::not_read;
    return in->rule->use;
  }
  if (name == "stamped_control" && ros2) return KeyUse::not_read;  // ROS 2's node does not declare it
  if (name == "use_control" && p.filter == filters::rl::RlFilterType::ukf) return KeyUse::no_effect;
  if ((k->needs == Needs::control && !p.control.enabled) ||
      (k->needs == Needs::smoothing && !p.smooth_lagged_data))
    return KeyUse::no_effect;
  return k->use;
}

KeyUse navsat_key_use(const std::string& name) {
  const Known* k = find_known(kNavsatKeys, name);
  return k ? k->use : KeyUse::not_read;
}

void report_keys(const Keys& keys, const std::string& section,
                 const std::function<KeyUse(const std::string&)>& use, std::vector<KeyReport>& out) {
  for (const auto& [name, e] : keys.order) out.push_back({section, name, e.key.Mark().line + 1, use(name)});
}

// One note listing the section's keys that change nothing in a replay.
void note_no_effect(const Reader& r, const Keys& keys, const std::vector<KeyReport>& reports) {
  std::string names;
  const YAML::Node* first = nullptr;
  for (const KeyReport& k : reports) {
    if (k.use != KeyUse::no_effect) continue;
    names += (names.empty() ? "" : ", ") + k.key;
    if (!first) first = &keys.find(k.key)->key;
  }
  if (!first) return;
  r.note(*first, fmt::format("{} change nothing in a replay (publishing, queues, logging, transform look-ups, "
                             "use_control's keys while it is off, history_length without smoothing): "
                             "accepted, no effect",
                             names));
}

bool flag(const Reader& r, const Keys& keys, const std::string& name, bool fallback = false) {
  const Entry* e = keys.find(name);
  return e ? r.boolean(name, e->value) : fallback;
}

double number(const Reader& r, const Keys& keys, const std::string& name, double fallback) {
  const Entry* e = keys.find(name);
  return e ? r.number(name, e->value) : fallback;
}

std::string text(const Reader& r, const Keys& keys, const std::string& name, const std::string& fallback) {
  const Entry* e = keys.find(name);
  return e ? r.text(name, e->value) : fallback;
}

// A number that must be finite and above (or at least) zero.
double positive(const Reader& r, const Keys& keys, const std::string& name, double fallback, bool zero_ok,
                std::string_view what) {
  const double v = number(r, keys, name, fallback);
  if (!std::isfinite(v) || v < 0.0 || (v == 0.0 && !zero_ok))
    r.fail(keys.find(name)->value, fmt::format("{} is {}, expected {}", name, v, what));
  return v;
}

double threshold(const Reader& r, const Keys& keys, const std::string& name) {
  const double v = number(r, keys, name, kNoRejection);
  if (v < 0.0)
    r.fail(keys.find(name)->value, fmt::format("{} is {}, expected a Mahalanobis distance >= 0", name, v));
  return v;
}

// 15 entries: the diagonal; 225: the matrix, row by row.
Matrix15 covariance(const Reader& r, const Keys& keys, const std::string& name, const Matrix15& fallback) {
  const Entry* e = keys.find(name);
  if (!e) return fallback;
  const std::vector<double> v = r.numbers(name, e->value);
  if (v.size() == 15) return Vector15(Eigen::Map<const Vector15>(v.data())).asDiagonal();
  if (v.size() != 225) {
    r.fail(e->value,
           fmt::format("{} has {} entries, expected 15 (the diagonal) or 225 (the matrix)", name, v.size()));
  }
  return Eigen::Map<const Eigen::Matrix<double, 15, 15, Eigen::RowMajor>>(v.data());
}

SensorParams read_input(const Reader& r, const Keys& keys, SensorKind kind, int index) {
  SensorParams s;
  s.kind = kind;
  s.index = index;
  s.name = fmt::format("{}{}", to_string(kind), index);
  const Entry& topic = *keys.find(s.name);
  s.topic = r.text(s.name, topic.value);
  s.yaml_line = topic.key.Mark().line + 1;
  if (const Entry* c = keys.find(s.name + "_config")) {
    const std::vector<bool> v = r.booleans(s.name + "_config", c->value);
    if (v.size() != 15) {
      r.fail(c->value,
             fmt::format("{}_config has {} entries, expected 15 booleans (x y z roll pitch yaw vx vy vz "
                         "vroll vpitch vyaw ax ay az)",
                         s.name, v.size()));
    }
    std::copy(v.begin(), v.end(), s.config.begin());
  }
  s.differential = flag(r, keys, s.name + "_differential");
  s.relative = flag(r, keys, s.name + "_relative") && !s.differential;  // the node prefers differential
  if (kind == SensorKind::odom) s.pose_use_child_frame = flag(r, keys, s.name + "_pose_use_child_frame");
  const bool own = kind == SensorKind::pose || kind == SensorKind::twist;  // poseN_rejection_threshold…
  if (kind != SensorKind::twist)
    s.pose_rejection_threshold = threshold(
        r, keys, s.name + (own ? "_rejection_threshold" : "_pose_rejection_threshold"));
  if (kind != SensorKind::pose)
    s.twist_rejection_threshold = threshold(
        r, keys, s.name + (own ? "_rejection_threshold" : "_twist_rejection_threshold"));
  if (kind == SensorKind::imu) {
    s.accel_rejection_threshold = threshold(r, keys, s.name + "_linear_acceleration_rejection_threshold");
    s.remove_gravitational_acceleration = flag(r, keys, s.name + "_remove_gravitational_acceleration");
  }
  return s;
}

// How many inputs of each kind the node reads: odom0, odom1, ... up to the first gap.
std::array<int, 4> input_counts(const Keys& keys) {
  std::array<int, 4> count{};
  for (const SensorKind k : kNodeOrder) {
    int& n = count[static_cast<std::size_t>(k)];
    while (keys.find(fmt::format("{}{}", to_string(k), n))) ++n;
  }
  return count;
}

RlParams read_ekf(const Reader& r, const Keys& keys, const std::string& section) {
  const std::array<int, 4> count = input_counts(keys);
  for (const auto& [name, e] : keys.order) check_ekf_key(r, name, e, count, section);
  RlParams p;
  p.frequency_hz = positive(r, keys, "frequency", 30.0, false, "a rate > 0 [Hz]");
  p.sensor_timeout_s = positive(r, keys, "sensor_timeout", 1.0 / p.frequency_hz, true, "a time >= 0 [s]");
  p.two_d_mode = flag(r, keys, "two_d_mode");
  p.predict_to_current_time = flag(r, keys, "predict_to_current_time");
  p.dynamic_process_noise_covariance = flag(r, keys, "dynamic_process_noise_covariance");
  p.gravitational_acceleration = number(r, keys, "gravitational_acceleration", 9.80665);
  p.map_frame = text(r, keys, "map_frame", "map");
  p.odom_frame = text(r, keys, "odom_frame", "odom");
  p.base_link_frame = text(r, keys, "base_link_frame", "base_link");
  p.world_frame = text(r, keys, "world_frame", p.odom_frame);
  p.process_noise_covariance = covariance(r, keys, "process_noise_covariance", default_process_noise());
  p.initial_estimate_covariance = covariance(r, keys, "initial_estimate_covariance",
                                             default_initial_estimate_covariance());
  if (const Entry* e = keys.find("initial_state")) {
    const std::vector<double> v = r.numbers("initial_state", e->value);
    if (v.size() != 15) {
      r.fail(e->value,
             fmt::format("initial_state has {} entries, expected 15 (x y z roll pitch yaw vx vy vz vroll "
                         "vpitch vyaw ax ay az)",
                         v.size()));
    }
    p.initial_state = Eigen::Map<const Vector15>(v.data());
  }
  for (const SensorKind k : kNodeOrder)
    for (int n = 0; n < count[static_cast<std::size_t>(k)]; ++n) p.sensors.push_back(read_input(r, keys, k, n));
  return p;
}

NavsatParams read_navsat(const Reader& r, const Keys& keys, const std::string& section) {
  for (const auto& [name, e] : keys.order) {
    const Known* k = find_known(kNavsatKeys, name);
    if (!k) {
      r.note(e.key, fmt::format("'{}' of {} is not one of navsat_transform_node's parameters, which does not "
                                "read it either (left out; check its spelling)",
                                name, section));
      continue;
    }
    if (name != "datum") r.check(name, e.value, k->kind);
    refuse_if_true(r, name, e);
  }
  NavsatParams n;
  n.present = true;
  n.node_name = section;
  n.frequency_hz = positive(r, keys, "frequency", 10.0, false, "a rate > 0 [Hz]");
  n.delay_s = positive(r, keys, "delay", 0.0, true, "a time >= 0 [s]");
  n.ros2 = r.ros2;
  n.magnetic_declination_radians = number(r, keys, "magnetic_declination_radians", 0.0);
  n.yaw_offset = number(r, keys, "yaw_offset", 0.0);
  n.zero_altitude = flag(r, keys, "zero_altitude");
  n.use_local_cartesian = flag(r, keys, "use_local_cartesian");
  n.use_odometry_yaw = flag(r, keys, "use_odometry_yaw");
  n.wait_for_datum = flag(r, keys, "wait_for_datum");
  if (const Entry* e = keys.find("datum")) {
    // latitude, longitude, heading; ROS 1 also accepted (and ignored) two frame names after them
    r.list("datum", e->value, "numbers");
    if (e->value.size() != 3 && (r.ros2 || e->value.size() < 3))
      r.fail(e->value, fmt::format("datum has {} entries, expected 3 (latitude [deg], longitude [deg], heading "
                                   "[rad])",
                                   e->value.size()));
    std::array<double, 3> d{};
    for (std::size_t i = 0; i < 3; ++i) d[i] = r.number(fmt::format("datum entry {}", i + 1), e->value[i]);
    if (n.wait_for_datum) n.datum = d;  // the node reads the datum only then
  }
  if (n.wait_for_datum && !n.datum) {
    r.fail(
        keys.find("wait_for_datum")->key,
        "wait_for_datum: true without a datum: navsat_transform_node then waits for a datum service call, "
        "which a bag does not hold; expected datum: [latitude, longitude, heading] or wait_for_datum: false");
  }
  return n;
}

// ---- sections ----------------------------------------------------------

struct Section {
  std::string name;     // "" for a flat ROS 1 file; "NAMESPACE/NODE" for a nested one
  YAML::Node key;       // the name's node (undefined for a flat file)
  YAML::Node params;    // the parameter mapping
  bool ros2 = false;    // NAME: {ros__parameters: {…}}
  bool nested = false;  // NAMESPACE: {NODE: {ros__parameters: {…}}} (ROS 2)
};

struct Layout {
  bool flat = false;
  std::vector<Section> sections;
  int ekf = -1;
  int navsat = -1;
};

bool has_input_key(const YAML::Node& map) {
  for (const auto& kv : map) {
    const auto in = kv.first.IsScalar() ? split_input_key(kv.first.Scalar()) : std::nullopt;
    if (in && in->rule && in->rule->suffix.empty()) return true;
  }
  return false;
}

bool has_navsat_key(const YAML::Node& map) {
  for (const auto& kv : map) {
    const std::string name = kv.first.IsScalar() ? kv.first.Scalar() : "";
    if (find_known(kNavsatKeys, name) &&
        std::find(std::begin(kSharedKeys), std::end(kSharedKeys), name) == std::end(kSharedKeys))
      return true;
  }
  return false;
}

// A top-level entry that is a node's section, ROS 2 (only child ros__parameters) or ROS 1.
std::optional<Section> section_of(const YAML::Node& key, const YAML::Node& value) {
  if (!key.IsScalar() || !value.IsMap()) return std::nullopt;
  const bool ros2 = value.size() == 1 && value.begin()->first.IsScalar() &&
                    value.begin()->first.Scalar() == "ros__parameters";
  // Constructed, not assigned: assigning one YAML::Node to another that is
  // bound rewrites the document it is bound into.
  const YAML::Node params = ros2 ? value.begin()->second : value;
  if (!params.IsMap()) return std::nullopt;
  return Section{key.Scalar(), key, params, ros2};
}

// ROS 2's namespaced form, NAMESPACE: {NODE: {ros__parameters: {…}}, …}: every
// entry of `value` a ROS 2 section.
bool is_namespace(const YAML::Node& value) {
  if (!value.IsMap() || value.size() == 0) return false;
  for (const auto& kv : value) {
    const auto s = section_of(kv.first, kv.second);
    if (!s || !s->ros2) return false;
  }
  return true;
}

std::string trim_slash(std::string_view s) { return std::string(s.starts_with('/') ? s.substr(1) : s); }

// A section asked for by name: its whole name, or for a nested one its node's.
bool named(const Section& s, const std::string& node_name) {
  const std::string want = trim_slash(node_name);
  if (trim_slash(s.name) == want) return true;
  return s.nested && s.name.substr(s.name.rfind('/') + 1) == want;
}

std::string names_of(const std::vector<Section>& sections, const std::vector<int>& which) {
  std::string out;
  for (const int i : which) out += (out.empty() ? "" : ", ") + sections[static_cast<std::size_t>(i)].name;
  return out.empty() ? "none" : out;
}

int pick_ekf(const Reader& r, const YAML::Node& root, const Layout& l, const std::string& node_name) {
  std::vector<int> all, candidates;
  for (int i = 0; i < static_cast<int>(l.sections.size()); ++i) {
    all.push_back(i);
    const Section& s = l.sections[static_cast<std::size_t>(i)];
    if (node_name.empty() ? has_input_key(s.params) : named(s, node_name)) candidates.push_back(i);
  }
  if (candidates.empty() && !node_name.empty())
    r.fail(root, fmt::format("no section '{}', expected one of {}", node_name, names_of(l.sections, all)));
  if (candidates.empty()) {
    r.fail(root, fmt::format("no ekf_node section: none has an odom0, pose0, twist0 or imu0 key (sections: {})",
                             names_of(l.sections, all)));
  }
  if (candidates.size() > 1) {
    r.fail(l.sections[static_cast<std::size_t>(candidates[1])].key,
           fmt::format("several ekf_node sections ({}), expected one or the node name of the one to read",
                       names_of(l.sections, candidates)));
  }
  return candidates[0];
}

// The node sections of a file's top level: NODE: {…} (ROS 1), NODE:
// {ros__parameters: {…}} (ROS 2), and each node of a NAMESPACE: {NODE: …}.
std::vector<Section> sections_of(const YAML::Node& root) {
  std::vector<Section> out;
  for (const auto& kv : root) {
    if (kv.first.IsScalar() && is_namespace(kv.second)) {
      for (const auto& node : kv.second) {
        Section s = *section_of(node.first, node.second);
        s.name = kv.first.Scalar() + "/" + s.name;
        s.nested = true;
        out.push_back(s);
      }
    } else if (auto s = section_of(kv.first, kv.second)) {
      out.push_back(*s);
    }
  }
  return out;
}

Layout locate(const Reader& r, const YAML::Node& root, const std::string& node_name) {
  if (root.IsNull()) r.fail(root, "the file is empty, expected robot_localization parameters");
  if (!root.IsMap()) {
    r.fail(root,
           "expected a mapping: NODE: {ros__parameters: {...}} (ROS 2), NODE: {...} or the keys (ROS 1), got " +
               describe(root));
  }
  Layout l;
  if (has_input_key(root)) {
    l.flat = true;
    l.sections.push_back(Section{"", YAML::Node(), root, false});
    l.ekf = 0;
    return l;
  }
  l.sections = sections_of(root);
  l.ekf = pick_ekf(r, root, l, node_name);
  std::vector<int> navsat;
  for (int i = 0; i < static_cast<int>(l.sections.size()); ++i)
    if (i != l.ekf && has_navsat_key(l.sections[static_cast<std::size_t>(i)].params)) navsat.push_back(i);
  if (navsat.size() > 1) {
    r.fail(l.sections[static_cast<std::size_t>(navsat[1])].key,
           fmt::format("several navsat_transform sections ({}), expected one", names_of(l.sections, navsat)));
  }
  if (!navsat.empty()) l.navsat = navsat[0];
  return l;
}

struct Source {
  fs::path file;
  std::string text;
  YAML::Node root;
};

Source parse(const fs::path& file, std::string text) {
  Source s{file, std::move(text), YAML::Node()};
  try {
    s.root = YAML::Load(s.text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(fmt::format("{}:{}: not valid YAML ({}), expected a ROS parameter file",
                                            file.string(), std::max(e.mark.line, 0) + 1, e.msg));
  }
  return s;
}

Source load(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::invalid_argument(fmt::format("{}: cannot open the parameter file", file.string()));
  std::ostringstream text;
  text << in.rdbuf();
  return parse(file, text.str());
}

constexpr std::string_view kUkfKeys[] = {"alpha", "kappa", "beta"};

// ekf_node or ukf_node (RlParams::filter): the command line's choice, else
// the section's name or ukf_node's keys; the UKF's constants.
void read_filter_type(const Reader& r, const Keys& keys, const std::string& section,
                      std::optional<filters::rl::RlFilterType> requested, RlParams& p) {
  const Entry* ukf_key = nullptr;
  for (const std::string_view k : kUkfKeys) {
    if (!ukf_key) ukf_key = keys.find(std::string(k));
  }
  if (requested == filters::rl::RlFilterType::ekf && ukf_key) {
    r.fail(ukf_key->key, fmt::format("{} is read by ukf_node only, and the filter asked for is ekf_node's "
                                     "(--filter ekf); expected --filter ukf or the key removed",
                                     ukf_key->key.Scalar()));
  }
  const bool named_ukf = section.find("ukf") != std::string::npos;
  p.filter = requested
                 ? *requested
                 : (named_ukf || ukf_key ? filters::rl::RlFilterType::ukf : filters::rl::RlFilterType::ekf);
  p.ukf.alpha = number(r, keys, "alpha", 0.001);
  p.ukf.kappa = number(r, keys, "kappa", 0.0);
  p.ukf.beta = number(r, keys, "beta", 2.0);
  filters::rl::RlUkfParams check;
  check.alpha = p.ukf.alpha;
  check.kappa = p.ukf.kappa;
  check.beta = p.ukf.beta;
  std::string why;
  if (p.filter == filters::rl::RlFilterType::ukf && !check.IsValid(&why))
    r.fail(ukf_key ? ukf_key->key : YAML::Node(), fmt::format("ukf_node's {}", why));
}

constexpr std::string_view kControlMembers = "vx, vy, vz, vroll, vpitch, vyaw";

// A list of 6 for use_control (`name`); nullopt when missing. `bools`: each
// entry true or false (ROS 1 also reads 0 and 1); else numbers.
std::optional<std::vector<double>> control_list(const Reader& r, const Keys& keys, const std::string& name,
                                                bool bools) {
  const Entry* e = keys.find(name);
  if (!e) return std::nullopt;
  r.list(name, e->value, bools ? "booleans" : "numbers");
  std::vector<double> v;
  for (std::size_t i = 0; i < e->value.size(); ++i) {
    const YAML::Node& x = e->value[i];
    const std::string what = fmt::format("{} entry {}", name, i + 1);
    if (!bools) {
      v.push_back(r.number(what, x));
    } else if (!r.ros2 && x.IsScalar() && (x.Scalar() == "0" || x.Scalar() == "1")) {
      v.push_back(x.Scalar() == "1" ? 1.0 : 0.0);
    } else {
      v.push_back(r.boolean(what, x) ? 1.0 : 0.0);
    }
  }
  return v;
}

filters::rl::ControlVector six(const std::vector<double>& v) {
  filters::rl::ControlVector out{};
  std::copy_n(v.begin(), std::min<std::size_t>(v.size(), out.size()), out.begin());
  return out;
}

// use_control off, as the node turns it off, with the reason noted.
void control_off(const Reader& r, const YAML::Node& at, RlParams& p, const std::string& why) {
  p.control.enabled = false;
  r.note(at, fmt::format("use_control: true, but {}: robot_localization then runs without a control term, "
                         "and so does the replay",
                         why));
}

// The limits and gains: both nodes default the limits to 1.0 and the
// deceleration's to the acceleration's; a gain list of another size is all
// 1.0. ROS 1 defaults the gains to 1.0; ROS 2 leaves a missing acceleration
// gain list empty and reads past it (undefined), taken as 1.0 here with a note.
bool read_control_limits(const Reader& r, const Keys& keys, RlParams& p) {
  filters::rl::RlControlParams& c = p.control.filter;
  const auto ones = std::vector<double>(6, 1.0);
  auto limits = [&](const std::string& name,
                    const std::vector<double>& fallback) -> std::optional<std::vector<double>> {
    const auto v = control_list(r, keys, name, false);
    if (!v) return fallback;
    if (v->size() == 6) return *v;
    control_off(r, keys.find(name)->key, p,
                fmt::format("{} has {} entries, not 6 ({})", name, v->size(), kControlMembers));
    return std::nullopt;
  };
  auto gains = [&](const std::string& name, const std::vector<double>& fallback) {
    const auto v = control_list(r, keys, name, false);
    if (!v) return fallback;
    if (v->size() == 6) return *v;
    r.note(keys.find(name)->key, fmt::format("{} has {} entries, not 6: robot_localization takes every gain as "
                                             "1.0, and so does the replay",
                                             name, v->size()));
    return ones;  // NOLINT(performance-no-automatic-move): captured by reference, a copy is meant
  };
  const auto accel = limits("acceleration_limits", ones);
  if (!accel) return false;
  const auto decel = limits("deceleration_limits", *accel);
  if (!decel) return false;
  if (r.ros2 && !keys.find("acceleration_gains")) {
    r.note(keys.find("use_control")->key,
           "use_control: true without acceleration_gains: ROS 2's node then reads gains from an empty list "
           "(undefined); the replay takes 1.0 for each, ROS 1's default");
  }
  const std::vector<double> accel_gains = gains("acceleration_gains", ones);
  c.acceleration_limits = six(*accel);
  c.deceleration_limits = six(*decel);
  c.acceleration_gains = six(accel_gains);
  c.deceleration_gains = six(gains("deceleration_gains", accel_gains));
  std::string why;
  if (!c.IsValid(&why)) r.fail(keys.find("use_control")->value, "use_control: " + why);
  return true;
}

// use_control and its keys (ros_filter.cpp loadParams), after the inputs are
// read: an IMU's fused linear acceleration takes that axis from the control.
void read_control(const Reader& r, const Keys& keys, RlParams& p) {
  const Entry* use = keys.find("use_control");
  if (!use || !r.boolean("use_control", use->value)) return;
  ControlParams& c = p.control;
  c.enabled = true;
  const double timeout = positive(r, keys, "control_timeout", r.ros2 ? 0.0 : p.sensor_timeout_s, true,
                                  "a time >= 0 [s]");
  c.filter.timeout_ns = static_cast<std::int64_t>(std::llround(timeout * 1e9));
  c.filter.timeout_rule = r.ros2 ? filters::rl::ControlTimeout::forward : filters::rl::ControlTimeout::absolute;
  if (const Entry* e = keys.find("stamped_control")) {
    if (r.ros2)
      r.note(e->key,
             "stamped_control is not read by ROS 2's node, which subscribes to geometry_msgs/Twist (left out)");
    else
      c.stamped = r.boolean("stamped_control", e->value);
  }
  const auto config = control_list(r, keys, "control_config", true);
  if (!config) return control_off(r, use->key, p, "control_config is missing");
  if (config->size() != 6)
    return control_off(r, keys.find("control_config")->key, p,
                       fmt::format("control_config has {} entries, not 6 ({})", config->size(),
                                   kControlMembers));
  for (int i = 0; i < 6; ++i) c.filter.update[i] = (*config)[i] != 0.0;
  if (!read_control_limits(r, keys, p)) return;
  for (const SensorParams& s : p.sensors) {
    for (int a = 0; a < 3; ++a) {
      if (s.kind != SensorKind::imu || !s.config[12 + a] || !c.filter.update[a]) continue;
      c.filter.update[a] = false;
      r.note(use->key, fmt::format(
                           "{} measures the {} acceleration, so robot_localization (and the replay) "
                           "takes {} out of control_config",
                           s.name, "xyz" [a], std::array { "vx", "vy", "vz" }[a]));
    }
  }
  if (std::none_of(c.filter.update.begin(), c.filter.update.end(), [](bool b) { return b; }))
    return control_off(r, keys.find("control_config")->key, p, "control_config leaves no member controlled");
  if (p.filter == filters::rl::RlFilterType::ukf) {
    c.enabled = false;
    r.note(use->key, "use_control: ukf_node computes the control term but its prediction does not apply it "
                     "(ukf.cpp), so the commands change nothing in its estimate, nor in the replay");
  }
}

// smooth_lagged_data and history_length (the node takes its magnitude; 0 by
// default, which keeps no history).
void read_smoothing(const Reader& r, const Keys& keys, RlParams& p) {
  p.smooth_lagged_data = flag(r, keys, "smooth_lagged_data");
  if (!p.smooth_lagged_data) return;
  const double h = std::abs(number(r, keys, "history_length", 0.0));
  if (!std::isfinite(h)) r.fail(keys.find("history_length")->value, "history_length must be finite [s]");
  p.history_length_ns = static_cast<std::int64_t>(std::llround(h * 1e9));
  if (p.control.enabled) {
    r.fail(keys.find("smooth_lagged_data")->key,
           "smooth_lagged_data: true with use_control: true is not reproduced by odotune's replay (the node "
           "re-filters with each message's own command), expected one of them false");
  }
}

RlParams read_layout(const Source& src, const Layout& l, std::optional<filters::rl::RlFilterType> filter) {
  const Section& ekf = l.sections[static_cast<std::size_t>(l.ekf)];
  std::vector<std::string> notes;
  const Reader r{src.file, ekf.ros2, &notes};
  const Keys keys = collect(r, ekf.params);
  RlParams p = read_ekf(r, keys, ekf.name.empty() ? "ekf_node" : ekf.name);
  read_filter_type(r, keys, ekf.name, filter, p);
  read_control(r, keys, p);
  read_smoothing(r, keys, p);
  const std::string section = ekf.name.empty() ? "ekf_node" : ekf.name;
  const std::array<int, 4> count = input_counts(keys);
  report_keys(
      keys, section, [&](const std::string& k) { return ekf_key_use(k, count, p, ekf.ros2); }, p.keys);
  note_no_effect(r, keys, p.keys);
  p.file = src.file;
  p.ros2 = ekf.ros2;
  p.node_name = ekf.name;
  if (l.navsat >= 0) {
    const Section& nav = l.sections[static_cast<std::size_t>(l.navsat)];
    const Reader rn{src.file, nav.ros2, &notes};
    const Keys nav_keys = collect(rn, nav.params);
    p.navsat = read_navsat(rn, nav_keys, nav.name);
    report_keys(nav_keys, nav.name, navsat_key_use, p.keys);
  }
  p.notes = std::move(notes);
  return p;
}

Layout locate(const Source& src, const std::string& node_name) {
  return locate(Reader{src.file, false}, src.root, node_name);
}

}  // namespace

namespace {

// navsat_transform_node's section of a file of its own: the keys at the top
// level (ROS 1), or the one section that has navsat's keys.
void read_navsat_file(const Source& src, RlParams& p) {
  const Reader r{src.file, false};
  if (!src.root.IsMap())
    r.fail(src.root, "expected navsat_transform_node's parameters, got " + describe(src.root));
  std::vector<Section> found;
  if (has_navsat_key(src.root)) {
    found.push_back(Section{"navsat_transform_node", YAML::Node(), src.root, false});
  } else {
    for (const Section& s : sections_of(src.root))
      if (has_navsat_key(s.params)) found.push_back(s);
  }
  if (found.size() != 1) {
    std::vector<int> all(found.size());
    for (std::size_t i = 0; i < found.size(); ++i) all[i] = static_cast<int>(i);
    r.fail(src.root, fmt::format("--navsat-params: expected one navsat_transform_node section, found {} ({})",
                                 found.size(), names_of(found, all)));
  }
  const Reader rn{src.file, found[0].ros2, &p.notes};
  const Keys keys = collect(rn, found[0].params);
  p.navsat = read_navsat(rn, keys, found[0].name);
  report_keys(keys, src.file.filename().string() + ": " + found[0].name, navsat_key_use, p.keys);
}

}  // namespace

RlParams read_navsat_params(const std::filesystem::path& file) {
  const Source src = load(file);
  const std::vector<Section> sections = src.root.IsMap() ? sections_of(src.root) : std::vector<Section>{};
  if ((src.root.IsMap() && has_input_key(src.root)) ||
      std::any_of(sections.begin(), sections.end(), [](const Section& s) { return has_input_key(s.params); })) {
    throw std::invalid_argument(fmt::format(
        "{}: has a filter section; expected navsat_transform_node's parameters alone", file.string()));
  }
  RlParams p;
  p.file = file;
  read_navsat_file(src, p);
  return p;
}

RlParams read_rl_params(const std::filesystem::path& file, const std::string& node_name,
                        std::optional<filters::rl::RlFilterType> filter,
                        const std::filesystem::path& navsat_file) {
  const Source src = load(file);
  RlParams p = read_layout(src, locate(src, node_name), filter);
  if (navsat_file.empty()) return p;
  if (p.navsat.present) {
    throw std::invalid_argument(
        fmt::format("{}: --navsat-params {}: this file has navsat_transform_node's section "
                    "({}) already; expected one of the two",
                    file.string(), navsat_file.string(), p.navsat.node_name));
  }
  read_navsat_file(load(navsat_file), p);
  return p;
}

// ---- writing ----------------------------------------------------------------

namespace {

// Shortest round-trip text with a '.' in the mantissa and a signed exponent, so
// that ROS 2 reads a double and PyYAML (ROS 1) a float: 30 -> "30.0", 1e-9 -> "1.0e-09".
std::string yaml_double(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  std::string s = fmt::format("{}", v);
  const std::size_t e = s.find('e');
  const std::string_view mantissa = std::string_view(s).substr(0, e);
  if (mantissa.find('.') == std::string_view::npos) s.insert(e == std::string::npos ? s.size() : e, ".0");
  return s;
}

// 15 rows of 15 entries, each column aligned; `col` is the column of the '['.
std::string flow_matrix(const Matrix15& m, std::size_t col) {
  std::array<std::string, 225> cells;
  std::array<std::size_t, 15> width{};
  for (std::size_t i = 0; i < 225; ++i) {
    cells[i] = yaml_double(m(static_cast<Eigen::Index>(i / 15), static_cast<Eigen::Index>(i % 15)));
    width[i % 15] = std::max(width[i % 15], cells[i].size());
  }
  std::string out = "[";
  for (std::size_t i = 0; i < 225; ++i) {
    if (i > 0 && i % 15 == 0) out += "\n" + std::string(col + 1, ' ');
    out += cells[i] + (i == 224 ? "]" : ",");
    if (i % 15 != 14) out.append(width[i % 15] - cells[i].size() + 1, ' ');
  }
  return out;
}

bool blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// Positions in the text from yaml-cpp's marks (line and column, 0-based).
struct Text {
  const std::string& s;
  std::vector<std::size_t> starts{0};

  explicit Text(const std::string& text) : s(text) {
    for (std::size_t i = 0; i < s.size(); ++i)
      if (s[i] == '\n') starts.push_back(i + 1);
  }
  std::size_t at(const YAML::Mark& m) const {
    return starts[static_cast<std::size_t>(m.line)] + static_cast<std::size_t>(m.column);
  }
  std::size_t line_end(std::size_t pos) const { return std::min(s.find('\n', pos), s.size()); }
  std::size_t line_start(std::size_t pos) const { return pos == 0 ? 0 : s.rfind('\n', pos - 1) + 1; }
};

// After the closing quote of the quoted scalar at `pos`.
std::size_t quoted_end(const std::string& s, std::size_t pos) {
  const char q = s[pos];
  for (std::size_t i = pos + 1; i < s.size(); ++i) {
    if (q == '"' && s[i] == '\\') {
      ++i;
    } else if (s[i] == q) {
      if (q == '\'' && i + 1 < s.size() && s[i + 1] == '\'') {
        ++i;
      } else {
        return i + 1;
      }
    }
  }
  return s.size();
}

// After the bracket closing the flow collection at `pos` (which may span lines).
std::size_t flow_end(const std::string& s, std::size_t pos) {
  int depth = 0;
  for (std::size_t i = pos; i < s.size(); ++i) {
    const char c = s[i];
    if (c == '"' || c == '\'') {
      i = quoted_end(s, i) - 1;
    } else if (c == '#' && i > pos && blank(s[i - 1])) {
      i = std::min(s.find('\n', i), s.size());
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if ((c == ']' || c == '}') && --depth == 0) {
      return i + 1;
    }
  }
  throw std::logic_error("unterminated flow collection");
}

// The end of a plain scalar: before a comment or the line's end, without trailing blanks.
std::size_t plain_end(const std::string& s, std::size_t pos) {
  std::size_t e = pos;
  while (e < s.size() && s[e] != '\n' && !(s[e] == '#' && e > pos && blank(s[e - 1]))) ++e;
  while (e > pos && blank(s[e - 1])) --e;
  return e;
}

// The end of a block value below its key (e.g. "- 0.1" lines): the last
// content line indented more than the key, or as much when it is a "- " item.
std::size_t block_end(const Text& t, std::size_t key_pos, std::size_t key_col) {
  std::size_t end = t.line_end(key_pos);
  for (std::size_t pos = end + 1; pos < t.s.size(); pos = t.line_end(pos) + 1) {
    const std::size_t first = t.s.find_first_not_of(" \t\r", pos);
    if (first == std::string::npos) break;
    if (t.s[first] == '\n' || t.s[first] == '#') continue;
    const std::size_t indent = first - pos;
    if (indent < key_col || (indent == key_col && t.s[first] != '-')) break;
    end = t.line_end(first);
    while (end > first && blank(t.s[end - 1])) --end;
  }
  return end;
}

// After the ':' that ends the key at `pos`.
std::size_t after_colon(const std::string& s, std::size_t pos) {
  std::size_t i = (s[pos] == '"' || s[pos] == '\'') ? quoted_end(s, pos) : pos;
  while (i < s.size() && !(s[i] == ':' && (i + 1 == s.size() || blank(s[i + 1])))) ++i;
  return std::min(i + 1, s.size());
}

// [after the key's ':', the end of its value).
std::pair<std::size_t, std::size_t> value_span(const Text& t, const Entry& e) {
  const std::size_t key = t.at(e.key.Mark()), begin = after_colon(t.s, key);
  if (e.value.IsNull()) return {begin, begin};
  std::size_t v = t.at(e.value.Mark());
  if (v < key) v = std::min(t.s.find_first_not_of(" \t", begin), t.s.size());  // an alias: the anchor's mark
  if (t.s[v] == '[' || t.s[v] == '{') return {begin, flow_end(t.s, v)};
  if (t.line_start(v) == t.line_start(key))
    return {begin, t.s[v] == '"' || t.s[v] == '\'' ? quoted_end(t.s, v) : plain_end(t.s, v)};
  return {begin, block_end(t, key, static_cast<std::size_t>(e.key.Mark().column))};
}

struct Edit {
  std::size_t begin = 0, end = 0;
  std::string text;
};

// A key to set: its value's text when it starts at a column; no function: remove the key.
struct Change {
  std::string key;
  std::function<std::string(std::size_t col)> value;
};

// The edits that apply `changes` to a block mapping in place: values replaced
// where they stand, keys removed with their lines, missing keys added after the
// last key at the mapping's indentation.
void edit_section(const Text& t, const Keys& keys, const std::vector<Change>& changes,
                  std::vector<Edit>& edits) {
  std::set<std::string> removed;
  std::string added;
  const auto indent = static_cast<std::size_t>(keys.order.front().second.key.Mark().column);
  for (const Change& c : changes) {
    const Entry* e = keys.find(c.key);
    if (e && c.value) {
      const auto [begin, end] = value_span(t, *e);
      edits.push_back({begin, end, " " + c.value(begin - t.line_start(begin) + 1)});
    } else if (e) {
      const std::size_t end = t.line_end(value_span(t, *e).second);
      edits.push_back({t.line_start(t.at(e->key.Mark())), std::min(end + 1, t.s.size()), ""});
      removed.insert(c.key);
    } else if (c.value) {
      added += "\n" + std::string(indent, ' ') + c.key + ": " + c.value(indent + c.key.size() + 2);
    }
  }
  if (added.empty()) return;
  // NOLINTNEXTLINE(modernize-loop-convert): clang 14 cannot compile libstdc++ 12's views::reverse
  for (auto it = keys.order.rbegin(); it != keys.order.rend(); ++it) {
    if (removed.count(it->first)) continue;
    const std::size_t at = t.line_end(value_span(t, it->second).second);
    edits.push_back({at, at, added});
    return;
  }
}

std::string apply(std::string s, std::vector<Edit> edits) {
  std::sort(edits.begin(), edits.end(), [](const Edit& a, const Edit& b) {
    return a.begin != b.begin ? a.begin > b.begin : a.end > b.end;
  });
  std::size_t limit = s.size();
  for (const Edit& e : edits) {
    if (e.end > limit) throw std::logic_error("overlapping edits of a parameter file");
    s.replace(e.begin, e.end - e.begin, e.text);
    limit = e.begin;
  }
  return s;
}

// The threshold keys of an input: pose, twist, acceleration ("" where it has none).
std::array<std::string, 3> threshold_keys(const SensorParams& s) {
  switch (s.kind) {
    case SensorKind::odom:
      return {s.name + "_pose_rejection_threshold", s.name + "_twist_rejection_threshold", ""};
    case SensorKind::imu:
      return {s.name + "_pose_rejection_threshold", s.name + "_twist_rejection_threshold",
              s.name + "_linear_acceleration_rejection_threshold"};
    case SensorKind::pose: return {s.name + "_rejection_threshold", "", ""};
    case SensorKind::twist: return {"", s.name + "_rejection_threshold", ""};
  }
  return {};
}

std::size_t sensor_index(const RlParams& p, const std::string& name) {
  for (std::size_t i = 0; i < p.sensors.size(); ++i)
    if (p.sensors[i].name == name) return i;
  throw std::invalid_argument(
      fmt::format("{}: no input '{}' in the ekf_node section, expected one of its odomN, "
                  "poseN, twistN or imuN",
                  p.file.string(), name));
}

// `p` with the update applied: what the written file must read back as.
RlParams updated(RlParams p, const RlParamsUpdate& u) {
  if (u.process_noise_covariance) p.process_noise_covariance = *u.process_noise_covariance;
  if (u.initial_estimate_covariance) p.initial_estimate_covariance = *u.initial_estimate_covariance;
  for (const auto& [name, thr] : u.rejection_thresholds) {
    SensorParams& s = p.sensors[sensor_index(p, name)];
    const auto keys = threshold_keys(s);
    for (std::size_t i = 0; i < 3; ++i) {
      if (keys[i].empty() && thr[i] != kNoRejection) {
        throw std::invalid_argument(
            fmt::format("{}: {} has no {} rejection threshold, expected kNoRejection there", p.file.string(),
                        name, std::array{"pose", "twist", "acceleration"}[i]));
      }
    }
    s.pose_rejection_threshold = keys[0].empty() ? s.pose_rejection_threshold : thr[0];
    s.twist_rejection_threshold = keys[1].empty() ? s.twist_rejection_threshold : thr[1];
    s.accel_rejection_threshold = keys[2].empty() ? s.accel_rejection_threshold : thr[2];
  }
  if (u.navsat_yaw_offset) {
    if (!p.navsat.present)
      throw std::invalid_argument(fmt::format("{}: no navsat_transform section to write yaw_offset to",
                                              p.file.string()));
    p.navsat.yaw_offset = *u.navsat_yaw_offset;
  }
  if (u.ukf) {
    p.filter = filters::rl::RlFilterType::ukf;
    p.ukf = *u.ukf;
  }
  return p;
}

std::function<std::string(std::size_t)> scalar(double v) {
  return [text = yaml_double(v)](std::size_t) { return text; };
}

std::function<std::string(std::size_t)> matrix(const Matrix15& m) {
  return [m](std::size_t col) { return flow_matrix(m, col); };
}

// The keys to set in the EKF section. `all_covariances`: also rewrite the
// covariances the file gives that the update leaves (as 15 rows of 15).
std::vector<Change> ekf_changes(const Keys& keys, const RlParams& cur, const RlParamsUpdate& u,
                                bool all_covariances) {
  std::vector<Change> out;
  const auto cov = [&](const char* key, const std::optional<Matrix15>& next, const Matrix15& now) {
    if (next)
      out.push_back({key, matrix(*next)});
    else if (all_covariances && keys.find(key))
      out.push_back({key, matrix(now)});
  };
  cov("process_noise_covariance", u.process_noise_covariance, cur.process_noise_covariance);
  cov("initial_estimate_covariance", u.initial_estimate_covariance, cur.initial_estimate_covariance);
  for (const auto& [name, thr] : u.rejection_thresholds) {
    const auto names = threshold_keys(cur.sensors[sensor_index(cur, name)]);
    for (std::size_t i = 0; i < 3; ++i) {
      if (names[i].empty()) continue;
      out.push_back({names[i], thr[i] == kNoRejection ? nullptr : scalar(thr[i])});
    }
  }
  if (u.ukf) {
    out.push_back({"alpha", scalar(u.ukf->alpha)});
    out.push_back({"kappa", scalar(u.ukf->kappa)});
    out.push_back({"beta", scalar(u.ukf->beta)});
  }
  return out;
}

// The source's text with the update applied in place.
std::string edit_in_place(const Source& src, const Layout& l, const RlParamsUpdate& u, bool all_covariances) {
  const RlParams cur = read_layout(src, l, std::nullopt);
  const Text t(src.text);
  std::vector<Edit> edits;
  const Section& ekf = l.sections[static_cast<std::size_t>(l.ekf)];
  const Reader r{src.file, ekf.ros2};
  const Keys ekf_keys = collect(r, ekf.params);
  edit_section(t, ekf_keys, ekf_changes(ekf_keys, cur, u, all_covariances), edits);
  if (u.navsat_yaw_offset && l.navsat >= 0) {
    const Section& nav = l.sections[static_cast<std::size_t>(l.navsat)];
    edit_section(t, collect(r, nav.params), {{"yaw_offset", scalar(*u.navsat_yaw_offset)}}, edits);
  }
  return apply(src.text, std::move(edits));
}

// Emits a value block style for mappings, flow style for sequences; quoted
// scalars stay quoted; with `as_double`, numbers as yaml_double writes them.
void emit(YAML::Emitter& out, const YAML::Node& n, bool as_double) {
  double d = 0.0;
  switch (n.Type()) {
    case YAML::NodeType::Scalar:
      if (as_double && n.Tag() != "!" && YAML::convert<double>::decode(n, d))
        out << yaml_double(d);
      else if (n.Tag() == "!")
        out << YAML::DoubleQuoted << n.Scalar();
      else
        out << n.Scalar();
      break;
    case YAML::NodeType::Sequence:
      out << YAML::Flow << YAML::BeginSeq;
      for (const auto& e : n) emit(out, e, as_double);
      out << YAML::EndSeq;
      break;
    case YAML::NodeType::Map:
      out << YAML::Block << YAML::BeginMap;
      for (const auto& kv : n) {
        out << YAML::Key;
        emit(out, kv.first, false);
        out << YAML::Value;
        emit(out, kv.second, false);
      }
      out << YAML::EndMap;
      break;
    default: out << YAML::Null;
  }
}

// A section's parameters; double-typed keys of the EKF or navsat section written as doubles.
void emit_params(YAML::Emitter& out, const YAML::Node& params, Kind (*kind_of)(std::string_view)) {
  out << YAML::Block << YAML::BeginMap;
  for (const auto& kv : params) {
    const Kind k = kind_of && kv.first.IsScalar() ? kind_of(kv.first.Scalar()) : Kind::any;
    out << YAML::Key;
    emit(out, kv.first, false);
    out << YAML::Value;
    emit(out, kv.second, k == Kind::number || k == Kind::numbers);
  }
  out << YAML::EndMap;
}

// The file rebuilt in the other form (or in block style); `ekf_name` is the
// EKF section's name there ("/**" for a flat ROS 1 file in ROS 2 form).
std::string rebuild(const Source& src, const Layout& l, bool ros2, std::string* ekf_name) {
  const auto kind_of = [&](const std::string& name) -> Kind (*)(std::string_view) {
    if (name == l.sections[static_cast<std::size_t>(l.ekf)].name) return ekf_kind;
    if (l.navsat >= 0 && name == l.sections[static_cast<std::size_t>(l.navsat)].name) return navsat_kind;
    return nullptr;
  };
  const auto section = [&](YAML::Emitter& out, const YAML::Node& params, const std::string& name) {
    if (!ros2) return emit_params(out, params, kind_of(name));
    out << YAML::Block << YAML::BeginMap << YAML::Key << "ros__parameters" << YAML::Value;
    emit_params(out, params, kind_of(name));
    out << YAML::EndMap;
  };
  YAML::Emitter out;
  *ekf_name = l.sections[static_cast<std::size_t>(l.ekf)].name;
  if (!ros2 && (l.flat || (l.sections.size() == 1 && *ekf_name == "/**"))) {
    emit_params(out, l.sections[0].params, ekf_kind);
    *ekf_name = "";
  } else if (l.flat) {
    out << YAML::Block << YAML::BeginMap << YAML::Key << "/**" << YAML::Value;
    section(out, src.root, "");
    out << YAML::EndMap;
    *ekf_name = "/**";
  } else {
    out << YAML::Block << YAML::BeginMap;
    for (const auto& kv : src.root) {
      out << YAML::Key;
      emit(out, kv.first, false);
      out << YAML::Value;
      if (const auto s = section_of(kv.first, kv.second))
        section(out, s->params, s->name);
      else
        emit(out, kv.second, false);
    }
    out << YAML::EndMap;
  }
  return std::string(out.c_str()) + "\n";
}

bool same_sensor(const SensorParams& a, const SensorParams& b) {
  return a.kind == b.kind && a.index == b.index && a.name == b.name && a.topic == b.topic &&
         a.config == b.config && a.differential == b.differential && a.relative == b.relative &&
         a.pose_rejection_threshold == b.pose_rejection_threshold &&
         a.twist_rejection_threshold == b.twist_rejection_threshold &&
         a.accel_rejection_threshold == b.accel_rejection_threshold &&
         a.remove_gravitational_acceleration == b.remove_gravitational_acceleration;
}

// Whether `b` (the written file) holds the same parameters as `a`, the name and form aside.
bool same_params(const RlParams& a, const RlParams& b) {
  const NavsatParams &n = a.navsat, &m = b.navsat;
  const auto same_ukf = [](const filters::rl::UkfConstants& x, const filters::rl::UkfConstants& y) {
    return x.alpha == y.alpha && x.kappa == y.kappa && x.beta == y.beta;
  };
  return a.filter == b.filter && (a.filter == filters::rl::RlFilterType::ekf || same_ukf(a.ukf, b.ukf)) &&
         a.frequency_hz == b.frequency_hz && a.sensor_timeout_s == b.sensor_timeout_s &&
         a.two_d_mode == b.two_d_mode && a.predict_to_current_time == b.predict_to_current_time &&
         a.dynamic_process_noise_covariance == b.dynamic_process_noise_covariance &&
         a.gravitational_acceleration == b.gravitational_acceleration && a.map_frame == b.map_frame &&
         a.odom_frame == b.odom_frame && a.base_link_frame == b.base_link_frame &&
         a.world_frame == b.world_frame && a.process_noise_covariance == b.process_noise_covariance &&
         a.initial_estimate_covariance == b.initial_estimate_covariance && a.initial_state == b.initial_state &&
         std::equal(a.sensors.begin(), a.sensors.end(), b.sensors.begin(), b.sensors.end(), same_sensor) &&
         n.present == m.present && n.frequency_hz == m.frequency_hz && n.delay_s == m.delay_s &&
         n.magnetic_declination_radians == m.magnetic_declination_radians && n.yaw_offset == m.yaw_offset &&
         n.zero_altitude == m.zero_altitude && n.use_local_cartesian == m.use_local_cartesian &&
         n.use_odometry_yaw == m.use_odometry_yaw && n.wait_for_datum == m.wait_for_datum && n.datum == m.datum;
}

std::string comment_lines(const std::string& text) {
  std::string out;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) out += line.empty() ? "#\n" : "# " + line + "\n";
  return out;
}

}  // namespace

std::string write_rl_params(const std::filesystem::path& original, const RlParams& params,
                            const RlParamsUpdate& update, bool ros2, const std::string& header_comment) {
  const Source src = load(original);
  const Layout l = locate(src, params.node_name);
  const RlParams expected = updated(read_layout(src, l, params.filter), update);
  const Section& ekf = l.sections[static_cast<std::size_t>(l.ekf)];
  const bool block = ekf.params.Style() != YAML::EmitterStyle::Flow &&
                     (l.navsat < 0 || l.sections[static_cast<std::size_t>(l.navsat)].params.Style() !=
                                          YAML::EmitterStyle::Flow);
  std::string note, text, name = ekf.name;
  if (ros2 == ekf.ros2 && block) {
    text = edit_in_place(src, l, update, false);
  } else if (ekf.nested) {
    throw std::invalid_argument(fmt::format(
        "{}: section {} is inside a namespace; odotune writes such a file only in its own form and block style "
        "(expected the ROS 2 form)",
        original.string(), ekf.name));
  } else {
    const Source rebuilt = parse(original, rebuild(src, l, ros2, &name));
    text = edit_in_place(rebuilt, locate(rebuilt, name), update, true);
    note = ros2 == ekf.ros2 ? fmt::format("# Rewritten from {} in block style; its comments are not kept.\n",
                                          original.filename().string())
                            : fmt::format("# Converted from the {} form of {}; its comments are not kept.\n",
                                          ekf.ros2 ? "ROS 2" : "ROS 1", original.filename().string());
  }
  const Source out = parse(original, text);
  // With the UKF's constants written, the file must say it is the UKF's by itself.
  const RlParams back = read_layout(out, locate(out, name),
                                    update.ukf ? std::nullopt : std::optional(params.filter));
  if (!same_params(expected, back) || back.ros2 != ros2) {
    throw std::logic_error(fmt::format(
        "{}: the rewritten parameters do not read back as written (an odotune bug)", original.string()));
  }
  return comment_lines(header_comment) + note + text;
}

}  // namespace odotune::rlnode

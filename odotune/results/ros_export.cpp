#include <odotune/results/ros_export.h>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <system_error>

#include <odotune/core/atomic_file.h>
#include <odotune/core/why.h>

namespace odotune::results {

const std::array<const char*, kRlStateSize> kRlStateNames = {
    "x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz", "vroll", "vpitch", "vyaw", "ax", "ay", "az"};

// Source: cra-ros-pkg/robot_localization, src/filter_base.cpp FilterBase::reset()
// ("These can be overridden via the launch parameters, but we need default
// values."), and the matrix in params/ekf.yaml documented as the default.
const std::array<double, kRlStateSize> kRlDefaultProcessNoiseDiagonal = {
    0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015};

namespace {

constexpr double kMm2PerM2 = 1e6;  // 1 m² = 1e6 mm²

// Shortest text that reads back to the identical double, always with a '.' in
// the mantissa ("50.0", "1.0e-05"): ROS 2 types a parameter by its literal and
// rejects an integer where robot_localization declares a double, and YAML 1.1
// readers (PyYAML, used by ROS 2 launch tooling) only take "1.0e-05", not
// "1e-05", as a float. Callers pass finite values only.
std::string double_literal(double v) {
  std::string s = fmt::format("{}", v);
  const auto e = s.find_first_of("eE");
  const std::string mantissa = s.substr(0, e);
  if (mantissa.find('.') == std::string::npos) s.insert(e == std::string::npos ? s.size() : e, ".0");
  return s;
}

// Text safe inside a '#' comment line: newlines flattened.
std::string one_line(std::string s) {
  std::replace_if(
      s.begin(), s.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
  return s;
}

bool valid_node_name(const std::string& name) {
  if (name.empty() || (name[0] >= '0' && name[0] <= '9')) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '/';
  });
}

bool finite_nonneg(double v) { return std::isfinite(v) && v >= 0.0; }
bool finite_pos(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

bool RosExportInput::IsValid(std::string* why) const {
  if (!valid_node_name(node_name))
    return core::invalid(why, fmt::format("node_name '{}' is not a ROS node name (letters, digits, '_', '/')",
                                          one_line(node_name)));
  if (!finite_nonneg(process_var_x_m2_per_s))
    return core::invalid(why, fmt::format("process_var_x_m2_per_s = {} must be finite and >= 0",
                                          process_var_x_m2_per_s));
  if (!finite_nonneg(process_var_y_m2_per_s))
    return core::invalid(why, fmt::format("process_var_y_m2_per_s = {} must be finite and >= 0",
                                          process_var_y_m2_per_s));
  if (!finite_nonneg(process_var_yaw_rad2_per_s))
    return core::invalid(why, fmt::format("process_var_yaw_rad2_per_s = {} must be finite and >= 0",
                                          process_var_yaw_rad2_per_s));
  if (!finite_pos(fix_var_x_m2))
    return core::invalid(why, fmt::format("fix_var_x_m2 = {} must be finite and > 0", fix_var_x_m2));
  if (!finite_pos(fix_var_y_m2))
    return core::invalid(why, fmt::format("fix_var_y_m2 = {} must be finite and > 0", fix_var_y_m2));
  if (!finite_pos(frequency_hz))
    return core::invalid(why, fmt::format("frequency_hz = {} must be finite and > 0", frequency_hz));
  return true;
}

RosExportInput ros_input_from_rq(double r1_mm2, double r2_mm2, double r3_rad2, double q1_mm2, double q2_mm2,
                                 double odometry_rate_hz) {
  if (!finite_pos(odometry_rate_hz))
    throw std::invalid_argument(fmt::format("ros_input_from_rq: odometry_rate_hz = {} must be finite and > 0",
                                            odometry_rate_hz));
  RosExportInput in;
  // odotune adds r once per prediction step, i.e. odometry_rate_hz times per
  // second; robot_localization adds Δt·Q per prediction (src/ekf.cpp,
  // Ekf::predict: `estimate_error_covariance_ += delta_sec * Q`), i.e. Q per
  // second. Equal growth per second: Q = r × odometry_rate_hz.
  // mm² → m²: divided by the exact 1e6 (one rounding, so 100 mm² × 50 Hz gives
  // exactly the double 0.005, not 0.004999999999999999).
  in.process_var_x_m2_per_s = r1_mm2 * odometry_rate_hz / kMm2PerM2;
  in.process_var_y_m2_per_s = r2_mm2 * odometry_rate_hz / kMm2PerM2;
  in.process_var_yaw_rad2_per_s = r3_rad2 * odometry_rate_hz;
  in.fix_var_x_m2 = q1_mm2 / kMm2PerM2;
  in.fix_var_y_m2 = q2_mm2 / kMm2PerM2;
  in.frequency_hz = odometry_rate_hz;
  in.tuned_params = {
      {"r1_mm2", r1_mm2}, {"r2_mm2", r2_mm2}, {"r3_rad2", r3_rad2}, {"q1_mm2", q1_mm2}, {"q2_mm2", q2_mm2}};
  return in;
}

namespace {

// Appends one line (and its newline) to the file's text.
struct LineOut {
  std::string& o;
  void operator()(const std::string& s) const {
    o += s;
    o += '\n';
  }
};

// The process noise: robot_localization's default diagonal with x, y and yaw
// replaced, as literals; `width` gets each column's widest.
std::array<std::string, kRlCovSize> q_cells(const RosExportInput& in,
                                            std::array<std::size_t, kRlStateSize>& width) {
  std::array<double, kRlCovSize> q{};
  for (std::size_t i = 0; i < kRlStateSize; ++i) q[i * kRlStateSize + i] = kRlDefaultProcessNoiseDiagonal[i];
  q[kRlX * kRlStateSize + kRlX] = in.process_var_x_m2_per_s;
  q[kRlY * kRlStateSize + kRlY] = in.process_var_y_m2_per_s;
  q[kRlYaw * kRlStateSize + kRlYaw] = in.process_var_yaw_rad2_per_s;

  std::array<std::string, kRlCovSize> cells;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    cells[k] = double_literal(q[k]);
    width[k % kRlStateSize] = std::max(width[k % kRlStateSize], cells[k].size());
  }
  return cells;
}

// What the file is and is not, its provenance and how to use it.
void write_header(const LineOut& line, const RosExportInput& in) {
  line("# robot_localization ekf_node parameters generated by odotune.");
  line("# What this is: the noise of odotune's 3-state pose EKF (x, y, yaw; odometry as the prediction)");
  line("# mapped onto robot_localization's 15-state process noise. It is NOT a tune of robot_localization's");
  line("# own filter, whose optimum differs (on the Husky recording this mapping makes a GPS outage worse");
  line("# than the defaults: docs/husky.md). To tune the filter the robot runs, from its bag and its own");
  line("# parameter file: odotune tune --rl-params YOUR_EKF.yaml --bag YOUR.bag --config-out OUT.yaml");
  if (!in.provenance.empty()) line("# Provenance: " + one_line(in.provenance));
  if (!in.tuned_params.empty()) {
    line("# Parameters as tuned (odotune units):");
    for (const auto& [name, value] : in.tuned_params)
      line(fmt::format("#   {} = {}", one_line(name), double_literal(value)));
  }
  line("#");
  line("# Use: ros2 run robot_localization ekf_node --ros-args --params-file THIS_FILE");
  line("# (merge the keys below into your existing ekf parameter file: inputs such as");
  line("# odom0 / pose0 and their *_config vectors are not set here).");
  line("#");
}

// How odotune's noise maps onto robot_localization's Q (odotune's rq model,
// or the caller's note), and the values.
void write_mapping(const LineOut& line, const RosExportInput& in) {
  if (in.mapping_note.empty()) {
    line("# Mapping from odotune's rq model (Kovacs et al. eq. 1, 2) to robot_localization:");
    line("#   odotune adds process noise r1 (x, mm²), r2 (y, mm²), r3 (yaw, rad²) once per");
    line("#   prediction step, i.e. once per odometry sample. robot_localization adds");
    line("#   delta_sec * process_noise_covariance per prediction (cra-ros-pkg/robot_localization");
    line("#   src/ekf.cpp, Ekf::predict: 'estimate_error_covariance_ += delta_sec * Q'), so its");
    line("#   Q is a variance per second. Equal variance growth per second gives:");
    line("#     Q[x][x]     [m²/s]   = r1 [mm²/step] × odometry rate [steps/s] × 1e-6 [m²/mm²]");
    line("#     Q[y][y]     [m²/s]   = r2 [mm²/step] × odometry rate [steps/s] × 1e-6 [m²/mm²]");
    line("#     Q[yaw][yaw] [rad²/s] = r3 [rad²/step] × odometry rate [steps/s]");
    line("#   (This conversion assumes robot_localization scales Q by Δt as above; it holds");
    line("#   whatever `frequency` the node runs at.)");
  } else {
    // Caller's explanation, one comment line per line of the note.
    std::size_t begin = 0;
    while (begin <= in.mapping_note.size()) {
      const std::size_t end = std::min(in.mapping_note.find('\n', begin), in.mapping_note.size());
      line("# " + one_line(in.mapping_note.substr(begin, end - begin)));
      begin = end + 1;
    }
  }
  line(fmt::format("#   Values here: Q[x][x] = {} m²/s, Q[y][y] = {} m²/s, Q[yaw][yaw] = {} rad²/s.",
                   double_literal(in.process_var_x_m2_per_s), double_literal(in.process_var_y_m2_per_s),
                   double_literal(in.process_var_yaw_rad2_per_s)));
  line("#   The other 12 diagonal entries are robot_localization's own defaults");
  line("#   (src/filter_base.cpp FilterBase::reset(), params/ekf.yaml); with two_d_mode");
  line("#   z, roll, pitch, vz, vroll, vpitch and az are ignored anyway. Off-diagonals are 0.");
  if (in.mapping_note.empty()) {
    line("#   odotune's alpha/gyro models (wheel-travel noise) have no constant entry in this");
    line("#   matrix: `odotune export` writes their time average over the tuning tracks instead.");
  }
  line("#");
}

// The position fixes' measurement noise, which robot_localization reads from
// the messages.
void write_fix_noise(const LineOut& line, const RosExportInput& in) {
  const std::string fx = double_literal(in.fix_var_x_m2), fy = double_literal(in.fix_var_y_m2);
  line("# Measurement noise of the absolute position fixes (odotune q1, q2):");
  line("#   robot_localization takes measurement covariance from each input message, not");
  line("#   from parameters. Set it in the position source's message (pose0:");
  line("#   geometry_msgs/PoseWithCovarianceStamped pose.covariance, or odom0:");
  line("#   nav_msgs/Odometry pose.covariance; 6 × 6 row-major over x, y, z, roll, pitch, yaw):");
  line(fmt::format("#     covariance[0] (x, x) = {} m²   (= q1 [mm²] × 1e-6; σ = {:.4g} m)", fx,
                   std::sqrt(in.fix_var_x_m2)));
  line(fmt::format("#     covariance[7] (y, y) = {} m²   (= q2 [mm²] × 1e-6; σ = {:.4g} m)", fy,
                   std::sqrt(in.fix_var_y_m2)));
  line("#   and fuse x, y from that input (pose0_config / odom0_config: true, true, false, ...).");
}

// The node's parameters: frequency, two_d_mode and the 15 × 15 Q, aligned in columns.
void write_parameters(const LineOut& line, const RosExportInput& in,
                      const std::array<std::string, kRlCovSize>& cells,
                      const std::array<std::size_t, kRlStateSize>& width) {
  line(in.node_name + ":");
  line("  ros__parameters:");
  line("    # Rate [Hz] of the filter's output/prediction loop (odotune: the odometry rate).");
  line("    frequency: " + double_literal(in.frequency_hz));
  line("    # Planar robot: z, roll, pitch and their rates are held at 0.");
  line(std::string("    two_d_mode: ") + (in.two_d_mode ? "true" : "false"));
  line("    # 15 × 15, row-major; rows/columns in state order");
  line("    #   x, y, z, roll, pitch, yaw, vx, vy, vz, vroll, vpitch, vyaw, ax, ay, az.");
  line("    # Units: m²/s (x, y, z), rad²/s (roll, pitch, yaw), (m/s)²/s, (rad/s)²/s, (m/s²)²/s.");
  line("    process_noise_covariance: [");
  for (int i = 0; i < kRlStateSize; ++i) {
    std::string row = "      ";
    for (int j = 0; j < kRlStateSize; ++j) {
      const std::string& c = cells[static_cast<std::size_t>(i) * kRlStateSize + static_cast<std::size_t>(j)];
      const bool last = (i == kRlStateSize - 1 && j == kRlStateSize - 1);
      std::string cell = c + (last ? "]" : ",");
      if (j + 1 < kRlStateSize) cell.resize(width[static_cast<std::size_t>(j)] + 2, ' ');
      row += cell;
    }
    row += fmt::format("  # {}", kRlStateNames[static_cast<std::size_t>(i)]);
    line(row);
  }
}

}  // namespace

std::string robot_localization_yaml(const RosExportInput& in) {
  std::string why;
  if (!in.IsValid(&why)) throw std::invalid_argument("robot_localization export: " + why);
  std::array<std::size_t, kRlStateSize> width{};  // per column
  const std::array<std::string, kRlCovSize> cells = q_cells(in, width);
  std::string o;
  const LineOut line{o};
  write_header(line, in);
  write_mapping(line, in);
  write_fix_noise(line, in);
  write_parameters(line, in, cells, width);
  return o;
}

namespace {

[[noreturn]] void parse_fail(const std::string& source, const YAML::Mark& mark, const std::string& what) {
  if (mark.is_null() || mark.line < 0) throw std::runtime_error(fmt::format("{}: {}", source, what));
  throw std::runtime_error(fmt::format("{}:{}: {}", source, mark.line + 1, what));
}

YAML::Node require(const YAML::Node& params, const char* key, const std::string& source, const YAML::Mark& at) {
  const YAML::Node n = params[key];
  if (!n) parse_fail(source, at, fmt::format("missing key '{}' under ros__parameters", key));
  return n;
}

std::string scalar_text(const YAML::Node& n) {
  return n.IsScalar() ? n.Scalar() : std::string("<not a scalar>");
}

}  // namespace

RosExportParsed parse_robot_localization_yaml(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    parse_fail(source, e.mark, "invalid YAML: " + e.msg);
  }
  if (!root.IsMap())
    parse_fail(source, root.Mark(), "expected a mapping 'NODE_NAME: {ros__parameters: ...}' at the top level");

  RosExportParsed out;
  YAML::Node params;
  for (const auto& entry : static_cast<const YAML::Node&>(root)) {
    if (!entry.second.IsMap()) continue;
    const YAML::Node p = entry.second["ros__parameters"];
    if (p && p.IsMap()) {
      out.node_name = entry.first.as<std::string>();
      params = p;
      break;
    }
  }
  if (!params) parse_fail(source, root.Mark(), "no top-level 'NODE_NAME: ros__parameters:' mapping found");
  const YAML::Mark at = params.Mark();

  const YAML::Node freq = require(params, "frequency", source, at);
  try {
    out.frequency_hz = freq.as<double>();
  } catch (const YAML::Exception&) {
    parse_fail(source, freq.Mark(),
               fmt::format("'frequency' is '{}', expected a number [Hz]", scalar_text(freq)));
  }
  const YAML::Node two_d = require(params, "two_d_mode", source, at);
  try {
    out.two_d_mode = two_d.as<bool>();
  } catch (const YAML::Exception&) {
    parse_fail(source, two_d.Mark(),
               fmt::format("'two_d_mode' is '{}', expected true or false", scalar_text(two_d)));
  }

  const YAML::Node m = require(params, "process_noise_covariance", source, at);
  if (!m.IsSequence())
    parse_fail(source, m.Mark(),
               "'process_noise_covariance' is not a list; expected 225 numbers (15 × 15, row-major)");
  if (m.size() != static_cast<std::size_t>(kRlCovSize))
    parse_fail(source, m.Mark(),
               fmt::format("'process_noise_covariance' has {} numbers, expected 225 (15 × 15, row-major)",
                           m.size()));
  for (std::size_t k = 0; k < static_cast<std::size_t>(kRlCovSize); ++k) {
    const YAML::Node e = m[k];
    try {
      if (!e.IsScalar()) throw YAML::Exception(e.Mark(), "not a scalar");
      out.process_noise_covariance[k] = e.as<double>();
    } catch (const YAML::Exception&) {
      parse_fail(
          source, e.Mark(),
          fmt::format("'process_noise_covariance' element {} (row {}, column {}) is '{}', expected a number", k,
                      k / kRlStateSize + 1, k % kRlStateSize + 1, scalar_text(e)));
    }
  }
  return out;
}

void write_robot_localization_yaml(const RosExportInput& in, const std::filesystem::path& path) {
  // Builds (and validates) the text before touching the disk.
  core::write_atomically(path, "robot_localization parameters", robot_localization_yaml(in));
}

}  // namespace odotune::results

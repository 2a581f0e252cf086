#include <odotune/formats/controller_config.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/core/failure.h>
#include <odotune/core/why.h>

namespace odotune::formats {

namespace {

using filters::OdometryParams;

std::string metres(double m) { return fmt::format("{:.7f}", m); }
std::string ratio(double r) { return fmt::format("{:.6f}", r); }

double mean_radius(const OdometryParams& p) { return 0.5 * (p.wheel_radius_left_m + p.wheel_radius_right_m); }

bool radii_differ(const OdometryParams& p) {
  return std::abs(p.wheel_radius_left_m - p.wheel_radius_right_m) >
         1e-12 * std::max(p.wheel_radius_left_m, p.wheel_radius_right_m);
}

// One parameter line: `NAME: VALUE  # meaning`.
struct Param {
  const char* name;
  std::string value;
  std::string meaning;
};

// The five parameters of `form` in the controllers' order, with what each is.
std::vector<Param> params_of(const ControllerGeometry& g, ControllerForm form) {
  const ControllerValues v = controller_values(g, form);
  const bool mult = form == ControllerForm::multipliers;
  return {
      {"wheel_separation", metres(v.wheel_separation_m), mult ? "D_nom [m]" : "D [m]"},
      {"wheel_radius", metres(v.wheel_radius_m), mult ? "R_nom [m]" : "(R_L + R_R) / 2 [m]"},
      {"wheel_separation_multiplier", ratio(v.wheel_separation_multiplier),
       mult ? "D / D_nom" : "1: D is wheel_separation itself"},
      {"left_wheel_radius_multiplier", ratio(v.left_wheel_radius_multiplier),
       mult ? "R_L / R_nom" : "R_L / wheel_radius"},
      {"right_wheel_radius_multiplier", ratio(v.right_wheel_radius_multiplier),
       mult ? "R_R / R_nom" : "R_R / wheel_radius"},
  };
}

std::string title(const ControllerOptions& o) {
  switch (o.kind) {
    case ControllerKind::ros2_control:
      return fmt::format("ros2_control diff_drive_controller parameters ({} form), written by odotune",
                         to_string(o.form));
    case ControllerKind::ros1:
      return fmt::format("ROS 1 diff_drive_controller parameters ({} form), written by odotune",
                         to_string(o.form));
    case ControllerKind::gazebo:
      return "Gazebo Sim DiffDrive system (gz::sim::systems::DiffDrive) geometry, written by odotune";
  }
  return "";
}

// The comment lines every kind opens with: what wrote the file, where the
// numbers come from, the calibrated and nominal geometry and the change.
std::vector<std::string> geometry_lines(const ControllerGeometry& g, const ControllerOptions& o) {
  std::vector<std::string> lines{title(o)};
  lines.insert(lines.end(), g.provenance.begin(), g.provenance.end());
  lines.insert(lines.end(), g.heldout.begin(), g.heldout.end());
  const OdometryParams &c = g.calibrated, &n = g.nominal;
  lines.emplace_back("");
  lines.push_back(fmt::format("calibrated geometry: R_L = {} m, R_R = {} m, D = {} m",
                              metres(c.wheel_radius_left_m), metres(c.wheel_radius_right_m),
                              metres(c.wheel_base_m)));
  lines.push_back(fmt::format(
      "nominal ({}): R_L = {} m, R_R = {} m, D = {} m", g.nominal_source.empty() ? "given" : g.nominal_source,
      metres(n.wheel_radius_left_m), metres(n.wheel_radius_right_m), metres(n.wheel_base_m)));
  if (radii_differ(n))
    lines.push_back(
        fmt::format("the nominal radii differ; the controller has one wheel_radius, so R_nom is their "
                    "mean, {} m",
                    metres(mean_radius(n))));
  lines.push_back(fmt::format("change against the nominal: left radius ×{}, right radius ×{}, wheel base ×{}",
                              ratio(c.wheel_radius_left_m / n.wheel_radius_left_m),
                              ratio(c.wheel_radius_right_m / n.wheel_radius_right_m),
                              ratio(c.wheel_base_m / n.wheel_base_m)));
  return lines;
}

// The comment lines after the geometry for ROS controllers: how the
// controller applies the values, the other form, what to merge.
std::vector<std::string> ros_lines(const ControllerGeometry& g, const ControllerOptions& o) {
  const bool ros2 = o.kind == ControllerKind::ros2_control;
  std::vector<std::string> lines{
      "The controller turns wheel rotation into motion (and commands into wheel speeds) with",
      "  radius of each wheel = wheel_radius × left/right_wheel_radius_multiplier",
      "  separation = wheel_separation × wheel_separation_multiplier",
      ros2 ? "(ros2_controllers diff_drive_controller/src/diff_drive_controller.cpp, parameters in "
             "src/diff_drive_controller_parameter.yaml)."
           : "(ros_controllers noetic-devel diff_drive_controller/src/diff_drive_controller.cpp).",
  };
  const ControllerForm other = o.form == ControllerForm::multipliers ? ControllerForm::absolute
                                                                     : ControllerForm::multipliers;
  lines.push_back(fmt::format("The same geometry in the {} form (--controller-form {}):", to_string(other),
                              to_string(other)));
  for (const Param& p : params_of(g, other))
    lines.push_back(fmt::format("  {}: {}  ({})", p.name, p.value, p.meaning));
  lines.emplace_back(
      ros2 ? "Merge these keys into your controller's ros__parameters; left_wheel_names, "
             "right_wheel_names and the rest stay yours."
           : "Merge these keys into your controller's parameters; left_wheel, right_wheel and the "
             "rest stay yours.");
  if (!ros2)
    lines.emplace_back("Do not also set wheel_radius_multiplier: when present it replaces both left and right "
                       "multipliers.");
  return lines;
}

std::string ros_text(const ControllerGeometry& g, const ControllerOptions& o) {
  std::string out;
  std::vector<std::string> lines = geometry_lines(g, o);
  const std::vector<std::string> more = ros_lines(g, o);
  lines.insert(lines.end(), more.begin(), more.end());
  for (const std::string& l : lines) out += l.empty() ? "#\n" : "# " + l + "\n";
  out += o.controller_name + ":\n";
  std::string indent = "  ";
  if (o.kind == ControllerKind::ros2_control) {
    out += "  ros__parameters:\n";
    indent = "    ";
  } else {
    out += "  type: diff_drive_controller/DiffDriveController\n";
  }
  for (const Param& p : params_of(g, o.form))
    out += fmt::format("{}{}: {}  # {}\n", indent, p.name, p.value, p.meaning);
  return out;
}

// XML comments may not hold "--".
std::string xml_comment_text(std::string s) {
  for (std::size_t p = s.find("--"); p != std::string::npos; p = s.find("--", p)) s.replace(p, 2, "- -");
  return s;
}

std::string gazebo_text(const ControllerGeometry& g, const ControllerOptions& o) {
  const OdometryParams& c = g.calibrated;
  const double r_mean = mean_radius(c), diff = c.wheel_radius_right_m - c.wheel_radius_left_m;
  std::vector<std::string> lines = geometry_lines(g, o);
  lines.emplace_back("");
  lines.emplace_back("Gazebo's DiffDrive has ONE wheel_radius for both wheels (gz-sim src/systems/diff_drive/"
                     "DiffDrive.cc, no multipliers):");
  lines.push_back(
      fmt::format("the calibrated left/right difference R_R - R_L = {:+.7f} m ({:+.3f} % of the mean "
                  "radius) cannot be represented here;",
                  diff, 100.0 * diff / r_mean));
  lines.emplace_back("wheel_radius is the mean (R_L + R_R) / 2, wheel_separation is D.");
  lines.emplace_back("Keep your <left_joint>, <right_joint> and other elements; replace these two.");
  std::string out;
  for (const std::string& l : lines) out += l.empty() ? "\n" : "<!-- " + xml_comment_text(l) + " -->\n";
  out += "<plugin filename=\"gz-sim-diff-drive-system\" name=\"gz::sim::systems::DiffDrive\">\n";
  out += fmt::format("  <wheel_separation>{}</wheel_separation>\n", metres(c.wheel_base_m));
  out += fmt::format("  <wheel_radius>{}</wheel_radius>\n", metres(r_mean));
  out += "</plugin>\n";
  return out;
}

}  // namespace

std::string_view to_string(ControllerKind kind) {
  switch (kind) {
    case ControllerKind::ros2_control: return "ros2_control";
    case ControllerKind::ros1: return "ros1";
    case ControllerKind::gazebo: return "gazebo";
  }
  return "?";
}

bool parse_controller_kind(std::string_view text, ControllerKind* out) {
  for (ControllerKind k : {ControllerKind::ros2_control, ControllerKind::ros1, ControllerKind::gazebo})
    if (text == to_string(k)) {
      if (out) *out = k;
      return true;
    }
  return false;
}

std::string_view to_string(ControllerForm form) {
  return form == ControllerForm::multipliers ? "multipliers" : "absolute";
}

bool parse_controller_form(std::string_view text, ControllerForm* out) {
  for (ControllerForm f : {ControllerForm::multipliers, ControllerForm::absolute})
    if (text == to_string(f)) {
      if (out) *out = f;
      return true;
    }
  return false;
}

bool ControllerOptions::IsValid(std::string* why) const {
  const std::string& n = controller_name;
  bool ok = !n.empty() && !std::isdigit(static_cast<unsigned char>(n.front()));
  for (char ch : n) ok = ok && (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '/');
  if (!ok)
    return core::invalid(
        why, fmt::format("controller_name '{}' is not a ROS name: expected letters, digits, '_' and '/', "
                         "not starting with a digit",
                         n));
  return true;
}

bool ControllerGeometry::IsValid(std::string* why) const {
  std::string bad;
  if (!calibrated.IsValid(&bad)) return core::invalid(why, "calibrated " + bad);
  if (!nominal.IsValid(&bad)) return core::invalid(why, "nominal " + bad + " (no nominal geometry given)");
  for (const auto* list : {&provenance, &heldout})
    for (const std::string& line : *list)
      if (line.find_first_of("\r\n") != std::string::npos)
        return core::invalid(why, fmt::format("a comment line holds a line break: '{}'",
                                              line.substr(0, line.find_first_of("\r\n"))));
  return true;
}

ControllerValues controller_values(const ControllerGeometry& g, ControllerForm form) {
  const OdometryParams &c = g.calibrated, &n = g.nominal;
  ControllerValues v;
  if (form == ControllerForm::multipliers) {
    v.wheel_radius_m = mean_radius(n);
    v.wheel_separation_m = n.wheel_base_m;
    v.wheel_separation_multiplier = c.wheel_base_m / n.wheel_base_m;
  } else {
    v.wheel_radius_m = mean_radius(c);
    v.wheel_separation_m = c.wheel_base_m;
    v.wheel_separation_multiplier = 1.0;
  }
  v.left_wheel_radius_multiplier = c.wheel_radius_left_m / v.wheel_radius_m;
  v.right_wheel_radius_multiplier = c.wheel_radius_right_m / v.wheel_radius_m;
  return v;
}

std::string controller_config_text(const ControllerGeometry& geometry, const ControllerOptions& options) {
  std::string why;
  if (!geometry.IsValid(&why) || !options.IsValid(&why)) throw core::Failure("controller file: " + why);
  return options.kind == ControllerKind::gazebo ? gazebo_text(geometry, options) : ros_text(geometry, options);
}

void write_controller_config(const ControllerGeometry& geometry, const ControllerOptions& options,
                             const std::filesystem::path& path) {
  std::string text;
  try {
    text = controller_config_text(geometry, options);
  } catch (const core::Failure& e) {
    throw core::Failure(fmt::format("{}: not written: {}", path.string(), e.what()));
  }
  try {
    core::write_atomically(path, "controller parameters", text);
  } catch (const std::runtime_error& e) {
    throw core::Failure(e.what());
  }
}

}  // namespace odotune::formats

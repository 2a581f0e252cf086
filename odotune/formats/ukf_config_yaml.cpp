#include <odotune/formats/ukf_config_yaml.h>

#include <cmath>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <odotune/core/failure.h>
#include <odotune/formats/config_yaml.h>
#include <odotune/formats/params_yaml.h>
#include <odotune/formats/yaml_error.h>

namespace odotune::formats {

namespace {

constexpr const char* kUkfConfigFormat = "odotune-ukf-config/1";

// The explanation block every written file carries.
constexpr const char* kExplanation =
    "The velocity-fusion UKF of Farina, Acosta, Toledo & Acosta, \"Improving Odometric Model\n"
    "Performance Based on LSTM Networks\", Sensors 2023, 23, 961, section 1 (odotune:\n"
    "odotune/filters/velocity_ukf.h, odotune/learned/ukf_fusion.h):\n"
    "  state       x = (V, W), body velocities [m/s, rad/s]\n"
    "  model       constant velocity, x_k = x_(k-1) + n with n ~ N(0, diag(q_v, q_w) * dt)\n"
    "  measures    every step: the kinematic wheel odometry (V, W) with the static variances\n"
    "              odo_var_v, odo_var_w; when the track has them: the external (lidar scan\n"
    "              matching) velocities with the track's v_ext_var/w_ext_var times\n"
    "              ext_var_scale, and the gyro's mean yaw rate over the step with gyro_var\n"
    "  pose        integrated from the filtered (V, W), paper eq. 3\n"
    "Variances are per fusion step at rate_hz (dt = 1/rate_hz): keep the rate.\n"
    "Larger q: the filter follows the measurements faster; larger odo_var_*: it trusts the\n"
    "wheels less (e.g. slip); ext_var_scale > 1: it trusts the external sensor less.";

double number_of(const std::filesystem::path& path, const YAML::Node& node, const std::string& what) {
  double v = 0.0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    fail_at(path, node, fmt::format("{} must be a number", what));
  }
  if (!std::isfinite(v) || v <= 0.0) fail_at(path, node, fmt::format("{} must be a finite number > 0", what));
  return v;
}

}  // namespace

learned::UkfSettings apply_ukf_config(const UkfConfig& config, const learned::UkfSettings& base) {
  return learned::apply_ukf_params(base, config.params);
}

UkfConfig read_ukf_config(const std::filesystem::path& path) {
  const YAML::Node root = load_format_file(path, "UKF configuration file", kUkfConfigFormat,
                                           "a mapping with format, rate_hz and params");
  static const std::set<std::string> known = {"format", "rate_hz", "params"};
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>("");
    if (!known.count(key))
      fail_at(path, kv.first, fmt::format("unknown key '{}', expected format, rate_hz or params", key));
  }
  for (const char* key : {"rate_hz", "params"})
    if (!root[key]) fail_at(path, root, fmt::format("'{}' is missing", key));

  UkfConfig cfg;
  cfg.rate_hz = number_of(path, root["rate_hz"], "rate_hz");
  learned::FusionInputOptions rate_check;
  rate_check.rate_hz = cfg.rate_hz;
  std::string why;
  if (!rate_check.IsValid(&why)) fail_at(path, root["rate_hz"], why);

  const objectives::BoxSpace space = learned::ukf_space();
  const YAML::Node params = root["params"];
  cfg.params = read_params_block(path, params, learned::ukf_space());
  if (!apply_ukf_config(cfg).IsValid(&why)) fail_at(path, params, "invalid settings: " + why);
  return cfg;
}

void write_ukf_config(const UkfConfig& config, const std::filesystem::path& path) {
  const objectives::BoxSpace space = learned::ukf_space();
  if (config.params.size() != space.dim())
    throw core::Failure(fmt::format("{}: {} UKF values given, expected {}", path.string(), config.params.size(),
                                    space.dim()));
  std::ostringstream out;
  if (!config.comment.empty()) {
    write_comment_lines(out, config.comment);
    out << "#\n";
  }
  write_comment_lines(out, kExplanation);
  out << "format: " << kUkfConfigFormat << "\n";
  out << fmt::format("rate_hz: {:.17g}  # fusion rate [Hz]; the variances below are per step at it\n",
                     config.rate_hz);
  write_params_block(out, space, config.params);
  write_file_atomically(path, out.str());
}

}  // namespace odotune::formats

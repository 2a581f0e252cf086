#include <odotune/formats/pf_config_yaml.h>

#include <cmath>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <odotune/calibration/calibration_objective.h>
#include <odotune/core/failure.h>
#include <odotune/formats/config_yaml.h>
#include <odotune/formats/params_yaml.h>
#include <odotune/formats/yaml_error.h>

namespace odotune::formats {

namespace {

constexpr const char* kPfConfigFormat = "odotune-pf-config/1";

std::string text_of(const std::filesystem::path& path, const YAML::Node& node, const char* key) {
  if (!node.IsScalar()) fail_at(path, node, fmt::format("'{}' must be a single word", key));
  return node.as<std::string>();
}

}  // namespace

filters::PfCalibratorParams apply_pf_config(const PfConfig& c, const filters::PfCalibratorParams& base) {
  filters::PfCalibratorParams p = calibration::apply_calibration_params(base, c.params);
  p.resampler = c.resampler;
  p.policy = c.policy;
  p.particles = c.particles;
  p.adaptive = c.method == calibration::CalibrationMethod::adaptive_pf;
  return p;
}

PfConfig read_pf_config(const std::filesystem::path& path) {
  const YAML::Node root = load_format_file(
      path, "PF configuration file", kPfConfigFormat,
      "a mapping with format, method, resampler, policy, particles and params");
  static const std::set<std::string> known = {"format", "method", "resampler", "policy", "particles", "params"};
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>("");
    if (!known.count(key))
      fail_at(path, kv.first,
              fmt::format("unknown key '{}', expected format, method, resampler, policy, particles or params",
                          key));
  }
  for (const char* key : {"method", "resampler", "policy", "particles", "params"})
    if (!root[key]) fail_at(path, root, fmt::format("'{}' is missing", key));

  PfConfig cfg;
  const YAML::Node method = root["method"];
  if (!calibration::parse_calibration_method(text_of(path, method, "method"), &cfg.method) ||
      (cfg.method != calibration::CalibrationMethod::pf &&
       cfg.method != calibration::CalibrationMethod::adaptive_pf))
    fail_at(path, method, "method must be pf or adaptive-pf");
  const YAML::Node resampler = root["resampler"];
  if (!filters::parse_resampler(text_of(path, resampler, "resampler"), &cfg.resampler))
    fail_at(path, resampler, "resampler must be multinomial, stratified, systematic or residual");
  const YAML::Node policy = root["policy"];
  if (!filters::parse_resample_policy(text_of(path, policy, "policy"), &cfg.policy))
    fail_at(path, policy, "policy must be every, neff or max");
  const YAML::Node particles = root["particles"];
  try {
    cfg.particles = particles.as<int>();
  } catch (const YAML::Exception&) {
    fail_at(path, particles, "particles must be a whole number ≥ 1");
  }
  if (cfg.particles < 1) fail_at(path, particles, "particles must be a whole number ≥ 1");

  const YAML::Node params = root["params"];
  cfg.params = read_params_block(path, params, calibration::calibration_space());
  std::string why;
  if (!apply_pf_config(cfg, filters::PfCalibratorParams{}).IsValid(&why))
    fail_at(path, params, "invalid settings: " + why);
  return cfg;
}

void write_pf_config(const PfConfig& config, const std::filesystem::path& path) {
  const objectives::BoxSpace space = calibration::calibration_space();
  if (config.params.size() != space.dim())
    throw core::Failure(fmt::format("{}: {} PF settings given, expected {}", path.string(),
                                    config.params.size(), space.dim()));
  std::ostringstream out;
  if (!config.comment.empty()) {
    write_comment_lines(out, config.comment);
  }
  out << "format: " << kPfConfigFormat << "\n";
  out << "method: " << calibration::to_string(config.method) << "  # pf | adaptive-pf\n";
  out << "resampler: " << filters::to_string(config.resampler)
      << "  # multinomial | stratified | systematic | residual\n";
  out << "policy: " << filters::to_string(config.policy) << "  # every | neff | max\n";
  out << "particles: " << config.particles << "  # N (pf) or initial N (adaptive-pf)\n";
  write_params_block(out, space, config.params);
  write_file_atomically(path, out.str());
}

}  // namespace odotune::formats

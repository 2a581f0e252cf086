#include <odotune/formats/config_yaml.h>

#include <cstdio>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <odotune/core/atomic_file.h>
#include <odotune/core/failure.h>
#include <odotune/formats/yaml_error.h>
#include <odotune/objectives/param_space.h>

namespace odotune::formats {

namespace {
constexpr const char* kConfigFormat = "odotune-ekf-config/1";

}  // namespace

void write_file_atomically(const std::filesystem::path& path, const std::string& text) {
  try {
    core::write_atomically(path, "file", text);
  } catch (const std::runtime_error& e) {
    throw core::Failure(e.what());
  }
}

EkfConfig read_ekf_config(const std::filesystem::path& path) {
  const YAML::Node root = load_format_file(path, "configuration file", kConfigFormat,
                                           "a mapping with format, model and params");
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>("");
    if (key != "format" && key != "model" && key != "params")
      fail_at(path, kv.first, fmt::format("unknown key '{}', expected format, model or params", key));
  }
  EkfConfig cfg;
  const YAML::Node model = root["model"];
  if (!model || !filters::parse_noise_model(model.as<std::string>(""), &cfg.model))
    fail_at(path, model ? model : root, "model must be rq, alpha or gyro");
  const objectives::ParamSpace space = objectives::ParamSpace::for_model(cfg.model);
  const YAML::Node params = root["params"];
  if (!params || !params.IsMap()) fail_at(path, params ? params : root, "expected a 'params' mapping");
  std::vector<double> values(space.dim());
  std::set<std::string> seen;
  for (const auto& kv : params) {
    const auto name = kv.first.as<std::string>("");
    const std::size_t i = space.index_of(name);
    if (i == space.dim()) {
      fail_at(path, kv.first,
              fmt::format("unknown parameter '{}' for model {}, expected {}", name,
                          filters::to_string(cfg.model), space.names()));
    }
    try {
      values[i] = kv.second.as<double>();
    } catch (const YAML::Exception&) {
      fail_at(path, kv.second, fmt::format("parameter '{}' must be a number", name));
    }
    seen.insert(name);
  }
  for (const auto& p : space.params())
    if (!seen.count(p.name)) fail_at(path, params, fmt::format("parameter '{}' is missing", p.name));
  cfg.noise = space.to_noise(values);
  std::string why;
  if (!cfg.noise.IsValid(&why)) fail_at(path, params, "invalid parameters: " + why);
  return cfg;
}

void write_ekf_config(const EkfConfig& config, const std::filesystem::path& path) {
  const objectives::ParamSpace space = objectives::ParamSpace::for_model(config.model);
  const std::vector<double> values = space.from_noise(config.noise);
  std::ostringstream out;
  if (!config.comment.empty()) {
    std::istringstream lines(config.comment);
    for (std::string line; std::getline(lines, line);) out << "# " << line << "\n";
  }
  out << "format: " << kConfigFormat << "\n";
  out << "model: " << filters::to_string(config.model) << "\n";
  out << "params:\n";
  for (std::size_t i = 0; i < space.dim(); ++i) {
    const auto& p = space.params()[i];
    out << fmt::format("  {}: {}  # [{}] {}, bounds {}..{}\n", p.name, values[i], p.unit, p.meaning, p.lower,
                       p.upper);
  }
  write_file_atomically(path, out.str());
}

}  // namespace odotune::formats

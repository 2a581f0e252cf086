// The `params:` block of the versioned settings files of the PF calibrator
// (pf_config_yaml.h) and the fusion UKF (ukf_config_yaml.h): one entry per
// parameter of a BoxSpace, by name, each a finite number > 0, written so that
// it reads back bit for bit with its unit, meaning and tuning bounds beside.
// (The EKF's older configuration file keeps its own reader: its messages
// name the noise model.)
#pragma once

#include <cmath>
#include <filesystem>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <odotune/formats/yaml_error.h>
#include <odotune/objectives/box_space.h>

namespace odotune::formats {

// Reads `params` (the node of key `params` in `path`): a mapping naming every
// parameter of `space` exactly once. One-line errors (FILE:LINE) otherwise.
inline std::vector<double> read_params_block(const std::filesystem::path& path, const YAML::Node& params,
                                             const objectives::BoxSpace& space) {
  if (!params.IsMap()) fail_at(path, params, "expected a 'params' mapping");
  std::vector<double> values(space.dim(), 0.0);
  std::set<std::string> seen;
  for (const auto& kv : params) {
    const auto name = kv.first.as<std::string>("");
    const std::size_t i = space.index_of(name);
    if (i == space.dim())
      fail_at(path, kv.first, fmt::format("unknown parameter '{}', expected {}", name, space.names()));
    if (!seen.insert(name).second) fail_at(path, kv.first, fmt::format("parameter '{}' is given twice", name));
    try {
      values[i] = kv.second.as<double>();
    } catch (const YAML::Exception&) {
      fail_at(path, kv.second, fmt::format("parameter '{}' must be a number", name));
    }
    if (!std::isfinite(values[i]) || values[i] <= 0.0)
      fail_at(path, kv.second, fmt::format("parameter '{}' must be a finite number > 0", name));
  }
  for (const auto& p : space.params())
    if (!seen.count(p.name)) fail_at(path, params, fmt::format("parameter '{}' is missing", p.name));
  return values;
}

// Writes "params:" and one commented line per parameter; {:.17g} reads back
// bit for bit. `values` has space.dim() entries.
inline void write_params_block(std::ostream& out, const objectives::BoxSpace& space,
                               const std::vector<double>& values) {
  out << "params:\n";
  for (std::size_t i = 0; i < space.dim(); ++i) {
    const auto& p = space.params()[i];
    out << fmt::format("  {}: {:.17g}  # [{}] {}; tuning bounds {}..{}\n", p.name, values[i], p.unit, p.meaning,
                       p.lower, p.upper);
  }
}

// Each line of `text` as a "# " comment line.
inline void write_comment_lines(std::ostream& out, const std::string& text) {
  std::string line;
  for (char c : text) {
    if (c == '\n') {
      out << "# " << line << "\n";
      line.clear();
    } else {
      line += c;
    }
  }
  if (!line.empty()) out << "# " << line << "\n";
}

}  // namespace odotune::formats

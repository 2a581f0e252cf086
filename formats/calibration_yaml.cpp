#include "formats/calibration_yaml.h"

#include <cmath>
#include <iterator>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "core/failure.h"
#include "formats/config_yaml.h"
#include "formats/yaml_error.h"

namespace odotune {

namespace {

constexpr const char* kFormat = "odotune-calibration/1";

struct Key {
  const char* name;
  double filters::OdometryParams::*field;
  const char* meaning;
};
const Key kKeys[] = {
    {"wheel_radius_left_m", &filters::OdometryParams::wheel_radius_left_m, "R_L [m]"},
    {"wheel_radius_right_m", &filters::OdometryParams::wheel_radius_right_m, "R_R [m]"},
    {"wheel_base_m", &filters::OdometryParams::wheel_base_m, "D [m], between the wheel contact points"},
};

std::string expected_keys() {
  std::string s = "format";
  for (const Key& k : kKeys) s += std::string(", ") + k.name;
  return s;
}

}  // namespace

CalibrationFile read_calibration_file(const std::filesystem::path& path) {
  const YAML::Node root = load_format_file(path, "calibration file", kFormat,
                                           fmt::format("a mapping with {}", expected_keys()));
  bool seen[std::size(kKeys)] = {};
  CalibrationFile file;
  for (const auto& kv : root) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : std::string();
    if (key == "format") continue;
    std::size_t i = 0;
    while (i < std::size(kKeys) && key != kKeys[i].name) ++i;
    if (i == std::size(kKeys))
      fail_at(path, kv.first, fmt::format("unknown key '{}', expected {}", key, expected_keys()));
    if (seen[i]) fail_at(path, kv.first, fmt::format("{} is given twice, expected it once", key));
    double value = 0.0;
    try {
      if (!kv.second.IsScalar()) throw YAML::Exception(kv.second.Mark(), "not a scalar");
      value = kv.second.as<double>();
    } catch (const YAML::Exception&) {
      fail_at(path, kv.second, fmt::format("{} must be a number in metres", key));
    }
    if (!std::isfinite(value) || value <= 0.0)
      fail_at(path, kv.second, fmt::format("{} = {} must be a finite number > 0 [m]", key, value));
    file.params.*kKeys[i].field = value;
    seen[i] = true;
  }
  for (std::size_t i = 0; i < std::size(kKeys); ++i)
    if (!seen[i]) fail_at(path, root, fmt::format("{} is missing", kKeys[i].name));
  return file;
}

std::string format_calibration_file(const CalibrationFile& file) {
  std::ostringstream out;
  if (!file.comment.empty()) {
    std::istringstream lines(file.comment);
    for (std::string line; std::getline(lines, line);) out << "# " << line << "\n";
  }
  out << "format: " << kFormat << "\n";
  for (const Key& k : kKeys) out << fmt::format("{}: {}  # {}\n", k.name, file.params.*k.field, k.meaning);
  return out.str();
}

void write_calibration_file(const CalibrationFile& file, const std::filesystem::path& path) {
  std::string why;
  if (!file.params.IsValid(&why)) throw Failure(fmt::format("{}: not written: {}", path.string(), why));
  write_file_atomically(path, format_calibration_file(file));
}

}  // namespace odotune

#include <odotune/formats/calibration_yaml.h>

#include <cmath>
#include <iterator>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <odotune/core/failure.h>
#include <odotune/formats/config_yaml.h>
#include <odotune/formats/yaml_error.h>

namespace odotune::formats {

namespace {

constexpr const char* kCalibrationFormat = "odotune-calibration/1";

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

struct TwistKey {
  const char* name;
  double filters::TwistCorrection::*field;
  const char* meaning;
  bool positive;  // else ≥ 0
};
const TwistKey kTwistKeys[] = {
    {"scale_v", &filters::TwistCorrection::scale_v, "v = scale_v · v_cmd(t − delay_s)", true},
    {"scale_w", &filters::TwistCorrection::scale_w, "w = scale_w · w_cmd(t − delay_s)", true},
    {"delay_s", &filters::TwistCorrection::delay_s, "[s], the motion lags v_cmd, w_cmd by this much", false},
};

std::string expected_keys() {
  std::string s = "format";
  for (const Key& k : kKeys) s += std::string(", ") + k.name;
  return s;
}

std::string expected_twist_keys() {
  std::string s = "format, odometry";
  for (const TwistKey& k : kTwistKeys) s += std::string(", ") + k.name;
  return s;
}

// A number under `key`, or a one-line error at its node.
double number_at(const std::filesystem::path& path, const YAML::Node& node, const std::string& key,
                 const char* unit) {
  try {
    if (!node.IsScalar()) throw YAML::Exception(node.Mark(), "not a scalar");
    return node.as<double>();
  } catch (const YAML::Exception&) {
    fail_at(path, node, fmt::format("{} must be a number{}", key, unit));
  }
}

// The body-velocity form (header comment).
void read_twist_keys(const std::filesystem::path& path, const YAML::Node& root, CalibrationFile& file) {
  bool seen[std::size(kTwistKeys)] = {};
  for (const auto& kv : root) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : std::string();
    if (key == "format" || key == "odometry") continue;
    std::size_t i = 0;
    while (i < std::size(kTwistKeys) && key != kTwistKeys[i].name) ++i;
    if (i == std::size(kTwistKeys))
      fail_at(path, kv.first,
              fmt::format("unknown key '{}' for odometry: {}, expected {}", key,
                          tracks::to_string(file.odometry), expected_twist_keys()));
    if (seen[i]) fail_at(path, kv.first, fmt::format("{} is given twice, expected it once", key));
    const double value = number_at(path, kv.second, key, "");
    if (!std::isfinite(value) || (kTwistKeys[i].positive ? value <= 0.0 : value < 0.0))
      fail_at(path, kv.second,
              fmt::format("{} = {} must be a finite number {}", key, value,
                          kTwistKeys[i].positive ? "> 0" : ">= 0"));
    file.twist.*kTwistKeys[i].field = value;
    seen[i] = true;
  }
  for (std::size_t i = 0; i < std::size(kTwistKeys); ++i)
    if (!seen[i]) fail_at(path, root, fmt::format("{} is missing", kTwistKeys[i].name));
}

}  // namespace

CalibrationFile read_calibration_file(const std::filesystem::path& path) {
  const YAML::Node root = load_format_file(path, "calibration file", kCalibrationFormat,
                                           fmt::format("a mapping with {}", expected_keys()));
  CalibrationFile file;
  if (const YAML::Node odometry = root["odometry"]) {
    if (!odometry.IsScalar() || !tracks::parse_odometry_input(odometry.Scalar(), &file.odometry))
      fail_at(path, odometry, "odometry must be wheels, twist or commands");
  }
  if (file.odometry != tracks::OdometryInput::wheels) {
    read_twist_keys(path, root, file);
    return file;
  }
  bool seen[std::size(kKeys)] = {};
  for (const auto& kv : root) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : std::string();
    if (key == "format" || key == "odometry") continue;
    std::size_t i = 0;
    while (i < std::size(kKeys) && key != kKeys[i].name) ++i;
    if (i == std::size(kKeys))
      fail_at(path, kv.first, fmt::format("unknown key '{}', expected {}", key, expected_keys()));
    if (seen[i]) fail_at(path, kv.first, fmt::format("{} is given twice, expected it once", key));
    const double value = number_at(path, kv.second, key, " in metres");
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
  out << "format: " << kCalibrationFormat << "\n";
  if (file.odometry != tracks::OdometryInput::wheels) {
    out << "odometry: " << tracks::to_string(file.odometry) << "\n";
    for (const TwistKey& k : kTwistKeys)
      out << fmt::format("{}: {}  # {}\n", k.name, file.twist.*k.field, k.meaning);
    return out.str();
  }
  for (const Key& k : kKeys) out << fmt::format("{}: {}  # {}\n", k.name, file.params.*k.field, k.meaning);
  return out.str();
}

void write_calibration_file(const CalibrationFile& file, const std::filesystem::path& path) {
  std::string why;
  const bool ok = file.odometry == tracks::OdometryInput::wheels ? file.params.IsValid(&why)
                                                                 : file.twist.IsValid(&why);
  if (!ok) throw core::Failure(fmt::format("{}: not written: {}", path.string(), why));
  write_file_atomically(path, format_calibration_file(file));
}

}  // namespace odotune::formats

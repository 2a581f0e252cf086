// Fixtures shared by the calibration-study tests (tests/studies) and the
// `odotune study` CLI tests (tests/cli): a short wheelchair scenario (~20 s
// instead of the 2-minute drive of scenarios/wheelchair.yaml) and a small CSV
// reader for the study's tables.
#pragma once

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/formats/scenario_yaml.h>

namespace odotune::study_fixtures {

constexpr double kNominalRadius = 0.32;

// The wheelchair of scenarios/wheelchair.yaml on a short drive with turns
// both ways; `step_at_s` > 0 adds a radius_step then.
inline std::string short_scenario(double step_at_s = 0.0) {
  std::string s =
      "name: short_chair\nseed: 1\n"
      "robot: {wheel_radius_left_m: 0.32, wheel_radius_right_m: 0.32, wheel_base_m: 0.65, ticks_per_rev: 8800}\n"
      "motion:\n  max_accel_m_s2: 0.4\n  max_angular_accel_rad_s2: 1.0\n  segments:\n"
      "    - stop: {duration_s: 1}\n"
      "    - straight: {distance_m: 4, speed_m_s: 0.8}\n"
      "    - arc: {radius_m: 1.0, angle_deg: 90, speed_m_s: 0.5}\n"
      "    - arc: {radius_m: 1.0, angle_deg: -120, speed_m_s: 0.5}\n"
      "    - straight: {distance_m: 3, speed_m_s: 0.8}\n"
      "    - spin: {angle_deg: 90, rate_deg_s: 45}\n"
      "    - stop: {duration_s: 1}\n"
      "sensors:\n  power: {enabled: false}\n  aps: {enabled: false}\n"
      "effects:\n  radius_error: {scale_l: 1.01, scale_r: 0.99}\n  wheel_base_error: {scale: 1.02}\n";
  if (step_at_s > 0.0)
    s += "  radius_step: {t: " + std::to_string(step_at_s) + ", scale_l: 0.985, scale_r: 0.99}\n";
  return s;
}

inline sim::Scenario parsed(double step_at_s = 0.0) {
  return odotune::formats::parse_scenario(short_scenario(step_at_s),
                                          step_at_s > 0 ? "short_step.yaml" : "short.yaml");
}

// CSV text → header and rows of fields.
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::size_t col(const std::string& name) const {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
  double num(std::size_t row, const std::string& name) const {
    const std::string& f = rows.at(row).at(col(name));
    return f.empty() ? NAN : std::stod(f);
  }
};

inline std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string f;
  while (std::getline(ss, f, ',')) out.push_back(f);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

inline Csv parse_csv(const std::string& text) {
  Csv c;
  std::stringstream ss(text);
  std::string line;
  std::getline(ss, line);
  c.header = split(line);
  while (std::getline(ss, line))
    if (!line.empty()) c.rows.push_back(split(line));
  return c;
}

// The CSV without its timing columns (ms_per_iter*).
inline std::string without_timing(const std::string& text) {
  const Csv c = parse_csv(text);
  std::string out;
  const auto keep = [&](std::size_t i) { return c.header[i].rfind("ms_per_iter", 0) != 0; };
  for (std::size_t i = 0; i < c.header.size(); ++i)
    if (keep(i)) out += c.header[i] + ",";
  out += "\n";
  for (const auto& r : c.rows) {
    for (std::size_t i = 0; i < r.size(); ++i)
      if (keep(i)) out += r[i] + ",";
    out += "\n";
  }
  return out;
}

}  // namespace odotune::study_fixtures

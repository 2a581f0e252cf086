// Reading a simulation scenario (src/tracks/scenario.h) from YAML.
//
// Schema (every key optional unless marked; see scenarios/README.md and the
// commented scenarios/track*.yaml for a full example):
//
//   name: track1                  # track name; default: the file stem
//   seed: 1                       # unsigned integer
//   step_s: 0.001                 # integration step [s]
//   robot:   { wheel_radius_left_m, wheel_radius_right_m, wheel_base_m, ticks_per_rev,
//              mass_kg, yaw_inertia_kg_m2, wheel_inertia_kg_m2, viscous_friction_nm_s,
//              coulomb_friction_nm, coulomb_smoothing_rad_s, torque_constant_nm_per_a,
//              coil_resistance_ohm }
//   motion:                       # REQUIRED
//     max_accel_m_s2: 0.5
//     max_angular_accel_rad_s2: 2.0
//     segments:                   # REQUIRED, a list of one-key maps:
//       - straight: {distance_m: 4, speed_m_s: 0.5}
//       - arc:      {radius_m: 0.6, angle_deg: 90, speed_m_s: 0.35}
//       - spin:     {angle_deg: -180, rate_deg_s: 90}
//       - stop:     {duration_s: 2}
//       - repeat:   {count: 3, segments: [ ... ]}      # expanded in place
//   sensors: { encoders | commands | gyro | power | ext_velocity | aps | ground_truth:
//              {enabled, rate_hz, <sigma_* / resolution_* of scenario.h>} }
//   effects: { <effect>: {<param>: value, ...}, ... }  # physics-effects.md names
//
// Errors: ScenarioError whose what() is one line "FILE:LINE: what is wrong;
// what was expected" (line 1-based, from YAML::Mark). Unknown keys are errors
// that suggest the closest valid key; every value is range-checked.
#pragma once

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include "tracks/scenario.h"

namespace odotune::cli {

class ScenarioError : public std::runtime_error {
 public:
  ScenarioError(std::string file, std::size_t line, const std::string& reason);
  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }  // 0 = whole file

 private:
  std::string file_;
  std::size_t line_;
};

// Reads and parses a scenario file; Scenario::source is the file name
// (without directories) and the default name is its stem.
sim::Scenario load_scenario(const std::filesystem::path& file);

// Parses scenario text; `filename` is used in messages and as the source.
sim::Scenario parse_scenario(std::string_view yaml_text, const std::string& filename);

}  // namespace odotune::cli

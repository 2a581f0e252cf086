// Reading a simulation scenario (odotune/sim/scenario.h) from YAML, and writing
// one (scenario_to_yaml, in scenario_yaml_write.cpp).
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
//   motion:                       # REQUIRED, with segments OR knots (not both)
//     start: {x_m: 0, y_m: 0, theta_rad: 0}   # initial pose [m, m, rad], each
//                                 # optional (default 0), finite; scenario.h
//     max_accel_m_s2: 0.5
//     max_angular_accel_rad_s2: 2.0
//     segments:                   # a non-empty list of one-key maps:
//       - straight: {distance_m: 4, speed_m_s: 0.5}
//       - arc:      {radius_m: 0.6, angle_deg: 90, speed_m_s: 0.35}
//       - spin:     {angle_deg: -180, rate_deg_s: 90}
//       - stop:     {duration_s: 2}
//       - repeat:   {count: 3, segments: [ ... ]}      # expanded in place
//     knots:                      # OR an explicit velocity profile: a non-empty
//       - [0.0, 0.0, 0.0]         # list of [t_s, v_m_s, w_rad_s] triples, first
//       - [0.5, 0.25, 0.0]        # t_s = 0, t_s strictly increasing; commands
//       - [4.0, 0.25, 0.1]        # linear between knots, taken as given (the
//                                 # acceleration limits are not applied)
//   sensors: { encoders | commands | gyro | power | ext_velocity | aps | ground_truth:
//              {enabled, rate_hz, <sigma_* / resolution_* of scenario.h>} }
//   effects: { <effect>: {<param>: value, ...}, ... }  # physics-effects.md names
//   slip_episodes:                # transient slips of one wheel (scenario.h SlipEpisode,
//     - {kind: spin, wheel: left, t0_s: 40, t1_s: 44, s: 0.6, ramp_s: 0.2}   # physics:
//     - {kind: hold, wheel: right, t0_s: 70, t1_s: 73, s: 0.5, brake_nm: 6} # simulator.h)
//                                 # kind spin|hold, wheel left|right, t0_s, t1_s, s
//                                 # required; ramp_s (default 0.2), brake_nm (hold
//                                 # only; default 0 = 2*coulomb_friction_nm) optional;
//                                 # 0 < s <= 0.9, 2*ramp_s <= t1_s - t0_s, no overlap
//                                 # on one wheel, t0_s before the motion's end
//   terms:                        # ground-speed corrections outside the effects
//     - {target: v_l, term: "v_l*sin(phi_l)", coef: 0.01}   # (odotune/sim/model_terms.h;
//                                 # names ASCII or as diagnose prints them, each
//                                 # (target, term) once, coef finite)
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

#include <odotune/sim/scenario.h>

namespace odotune::formats {

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

// The scenario as YAML in the schema above, which parse_scenario reads back
// to the same scenario field by field (every field the reader reads: name,
// seed, step_s, all robot fields, motion with its start pose (all three
// fields, written only when one of them is non-zero, so a scenario starting
// at the origin is written as before; -0 counts as zero and reads back as 0)
// and its segments (flat, one line each, only the fields of the segment's
// kind) or knots (one [t_s, v_m_s, w_rad_s] line each), every field of every
// sensor, the active effects with
// all their parameters, the slip episodes (all fields but line; brake_nm for
// hold only; the key omitted when there are none), the model terms (ASCII
// names; the key omitted when there are none); numbers in shortest round-trip form, so they parse
// back bit for bit). Not written: Scenario::source (the reader sets it from
// the file name) and Segment::line. `header_comment` goes first, each of its
// lines prefixed "# " (nothing for ""). Throws std::invalid_argument for a
// scenario the reader would reject: invalid (validate_scenario's message),
// no segments and no knots, an empty or multi-line name, a non-finite number.
std::string scenario_to_yaml(const sim::Scenario& scenario, const std::string& header_comment);

}  // namespace odotune::formats

// A simulator scenario that re-drives a track: the robot of the track, its
// sensors at their rates, a given set of physics effects (e.g. the ones a
// diagnosis fitted), and as motion the explicit velocity knots (scenario.h,
// motion_profile.h) that make the simulated robot, WITH those effects, drive
// the track's reference path (ground truth, else the position fixes). How the
// knots are fitted, which effects are inverted and which need not be:
// docs/simulator.md, "Re-driving a track". Units SI.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <odotune/sim/scenario.h>
#include <odotune/tracks/track.h>

namespace odotune::sim {

struct ScenarioFromTrackOptions {
  std::uint64_t seed = 1;            // the scenario's noise seed
  double knot_rate_hz = 10.0;        // knots per second, in (0, 1000]
  double half_window_s = 0.5;        // smoothing half-width [s], > 0
  double fixes_half_window_s = 2.0;  // the same for a position-fix reference [s]
  std::size_t min_fit_points = 6;    // at least this many samples per local fit, >= 4
  double min_speed_m_s = 0.02;       // heading-from-path speed threshold [m/s], >= 0
  double step_s = 0.001;             // the scenario's integration step [s]

  bool IsValid(std::string* why) const;
};

// The scenario described in the file comment. `effect_specs` are in the
// simulator's command-line form ("lateral_skid:k=0.021", effects.h), applied
// in order. Throws std::invalid_argument: a bad spec (the message contains the
// spec), a track without a reference path, with fewer than 3 reference
// samples or longer than the simulator accepts (naming the track), invalid
// options, or a scenario the simulator would reject (validate_scenario's
// message).
Scenario scenario_from_track(const tracks::Track& track, const std::vector<std::string>& effect_specs,
                             const ScenarioFromTrackOptions& options = {});

}  // namespace odotune::sim

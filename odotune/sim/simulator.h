// The differential-drive robot simulator: Scenario (scenario.h) -> Track.
// Deterministic: the same scenario and seed give a bit-identical Track (and so
// a byte-identical file) on the same build; each sensor has its own seeded
// stream, so switching one sensor or effect on or off never changes another
// sensor's noise. The world model (controller, wheels, effects, sensors, motor
// power, slip episodes) and its sources: docs/simulator.md. Units SI.
#pragma once

#include <string>

#include <odotune/sim/scenario.h>
#include <odotune/tracks/track.h>

namespace odotune::sim {

// Checks every field (ranges, sample periods being whole numbers of steps, the
// motion profile, a bound on the size of the result). On failure `why` is one
// line naming the field, its value and what was expected.
bool validate_scenario(const Scenario& scenario, std::string* why);

// Runs the simulation. Throws std::invalid_argument with validate_scenario's
// message for an invalid scenario.
tracks::Track simulate(const Scenario& scenario);

// Upper bounds enforced by validate_scenario (no unbounded allocation).
inline constexpr double kMaxSimSteps = 2e8;
inline constexpr double kMaxSimRows = 1e7;

}  // namespace odotune::sim

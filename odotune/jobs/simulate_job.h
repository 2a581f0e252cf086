// `odotune simulate`: a scenario YAML (odotune/formats/scenario_yaml.h), changed by
// the command's overrides, simulated (odotune/sim/simulator.h) and written as a
// track file. The command reads the flags and prints the summary line.
//
// Overrides, in this order:
//   seed         replaces the scenario's noise seed;
//   random_slip  replaces the scenario's slip episodes with a random layout
//                drawn with that seed (odotune/sim/random_slip.h): training drives
//                for the slip detector;
//   no_effects   drops the file's effects;
//   effects      "NAME:param=value,..." applied after the file's effects: a
//                new effect is switched on (unset optional parameters take
//                their defaults), an effect the file already has keeps its
//                parameters except those given (odotune/sim/effects.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <odotune/tracks/track.h>

namespace odotune::jobs {

struct SimulateRequest {
  std::string scenario;  // scenario YAML file
  std::string output;    // track file to write
  // Seeds as given on the command line ("" = not given), parsed here so that
  // "-1" is an error rather than 2^64 - 1.
  std::string seed;
  std::string random_slip;
  std::vector<std::string> effects;
  bool no_effects = false;
};

// What the summary line reports.
struct SimulateOutcome {
  std::string track_name;
  std::size_t rows = 0;
  double duration_s = 0.0;
  double path_length_m = 0.0;  // along the ground truth
  std::uint64_t seed = 0;      // the noise seed used
  std::string effects;         // the effects simulated (sim::format_effects)
  std::size_t slip_episodes = 0;
};

// Throws core::Failure (one line) on an unreadable or invalid scenario, an
// output that is the scenario file itself, a bad seed or effect, a drive with
// no room for a random slip episode, or a track that cannot be written.
SimulateOutcome run_simulate(const SimulateRequest& request);

// Path length [m] along the ground truth (0 without it); NaN rows skipped.
double path_length_m(const tracks::Track& track);

}  // namespace odotune::jobs

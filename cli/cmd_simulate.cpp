// `odotune simulate`: scenario YAML -> simulated track file.
//
//   odotune simulate SCENARIO.yaml -o TRACK.csv [--seed N]
//                    [--effect NAME:param=value,...]... [--no-effects]
//                    [--random-slip N]
//   odotune simulate --list-effects
//
// Effects given with --effect are applied after the file's effects: a new
// effect is switched on (unset optional parameters take their defaults), an
// effect the file already has keeps its parameters except those given.
// --no-effects drops the file's effects first (so --no-effects with --effect
// gives exactly the command-line effects). --random-slip N replaces the
// scenario's slip episodes with a random layout drawn with seed N
// (tracks/random_slip.h): training drives for the slip detector.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/commands.h"
#include "core/failure.h"
#include "formats/scenario_yaml.h"
#include "tracks/effects.h"
#include "tracks/motion_profile.h"
#include "tracks/random_slip.h"
#include "tracks/simulator.h"
#include "tracks/track_io.h"

namespace odotune::cli {

namespace {

struct SimulateOptions {
  std::string scenario;
  std::string output;
  std::string seed;  // parsed here: CLI11 would wrap "-1" around to 2^64-1
  std::string random_slip;  // seed of a random slip-episode layout ("" = the scenario's episodes)
  std::vector<std::string> effects;
  bool no_effects = false;
  bool list_effects = false;
};

void print_effect_table(std::ostream& out) {
  out << "Effects (../shared/specs/physics-effects.md); use --effect NAME:param=value,...\n";
  for (const auto& e : sim::effect_table()) {
    out << fmt::format("  {}: {}\n", e.name, e.meaning);
    for (const auto& p : e.params)
      out << fmt::format("      {:<8} [{}] {}, range {}{}, {}]{}\n", p.name, p.unit, p.meaning,
                         p.min_exclusive ? "(" : "[", p.min, p.max,
                         p.required ? ", required" : fmt::format(", default {}", p.default_value));
  }
}

// Path length [m] along the ground truth, for the summary line.
double path_length_m(const Track& track) {
  if (!track.has_gt()) return 0.0;
  const auto& x = track.col(Col::gt_x);
  const auto& y = track.col(Col::gt_y);
  double len = 0.0, px = 0.0, py = 0.0;
  bool have = false;
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (std::isnan(x[i]) || std::isnan(y[i])) continue;
    if (have) len += std::hypot(x[i] - px, y[i] - py);
    px = x[i], py = y[i], have = true;
  }
  return len;
}

void run_simulate(const SimulateOptions& o) {
  if (o.list_effects) {
    print_effect_table(std::cout);
    return;
  }
  if (o.scenario.empty())
    throw Failure("simulate: missing SCENARIO.yaml; expected: odotune simulate SCENARIO.yaml -o TRACK.csv");
  if (o.output.empty())
    throw Failure("simulate: missing -o TRACK.csv; expected: odotune simulate SCENARIO.yaml -o TRACK.csv");

  sim::Scenario sc;
  try {
    sc = load_scenario(o.scenario);
  } catch (const ScenarioError& e) {
    throw Failure(e.what());
  }
  {
    std::error_code ec;
    if (std::filesystem::exists(o.output, ec) && std::filesystem::equivalent(o.output, o.scenario, ec))
      throw Failure(fmt::format("simulate: -o {} is the scenario file itself; expected a track file name",
                                o.output));
  }
  const auto parse_seed = [](const char* flag, const std::string& text) {
    std::uint64_t seed = 0;
    const char* end = text.data() + text.size();
    const auto [p, ec] = std::from_chars(text.data(), end, seed);
    if (ec != std::errc() || p != end)
      throw Failure(fmt::format("{} {}: expected a non-negative integer below 2^64", flag, text));
    return seed;
  };
  if (!o.seed.empty()) sc.seed = parse_seed("--seed", o.seed);
  if (!o.random_slip.empty()) {
    const std::uint64_t layout = parse_seed("--random-slip", o.random_slip);
    try {
      sc.slip_episodes = sim::random_slip_episodes(sim::MotionProfile(sc.motion), layout);
    } catch (const std::exception& e) {  // the profile was validated with the scenario
      throw Failure(fmt::format("{}: --random-slip: {}", o.scenario, e.what()));
    }
    if (sc.slip_episodes.empty())
      throw Failure(fmt::format("{}: --random-slip {}: the drive has no stretch long and fast enough for a slip "
                                "episode (>= 2 s at >= 0.3 m/s); expected a longer drive",
                                o.scenario, o.random_slip));
  }
  if (o.no_effects) sc.effects = sim::Effects{};
  for (const auto& text : o.effects) {
    sim::EffectSpec spec;
    try {
      spec = sim::parse_effect_spec(text);
    } catch (const std::invalid_argument& e) {
      throw Failure(fmt::format("--{}", e.what()));  // "--effect 'TEXT': ..."
    }
    try {
      sim::apply_effect(sc.effects, spec);
    } catch (const std::invalid_argument& e) {
      throw Failure(fmt::format("--effect '{}': {}", text, e.what()));
    }
  }

  Track track = [&] {
    try {
      return sim::simulate(sc);
    } catch (const std::invalid_argument& e) {
      throw Failure(fmt::format("{}: {}", o.scenario, e.what()));
    }
  }();
  try {
    write_track(track, o.output);
  } catch (const std::exception& e) {
    throw Failure(e.what());
  }
  std::cout << fmt::format("wrote {}: track '{}', {} rows over {:.1f} s, path {:.1f} m, seed {}, effects: {}",
                           o.output, track.name(), track.size(), track.duration_s(), path_length_m(track),
                           sc.seed, sim::format_effects(sc.effects));
  if (!sc.slip_episodes.empty())
    std::cout << fmt::format(", {} slip episode{}{}", sc.slip_episodes.size(), sc.slip_episodes.size() == 1 ? "" : "s",
                             o.random_slip.empty() ? "" : fmt::format(" (random layout {})", o.random_slip));
  std::cout << "\n";
}

}  // namespace

void register_simulate(CLI::App& app) {
  auto opts = std::make_shared<SimulateOptions>();
  auto* sub = app.add_subcommand(
      "simulate",
      "Simulate a differential-drive robot from a YAML scenario and write a track (odotune-track/1).\n"
      "Example: odotune simulate scenarios/track1.yaml -o track1.csv --seed 7 "
      "--effect lateral_skid:k=0.02 --effect radius_error:scale_l=0.995,scale_r=1.004");
  sub->add_option("scenario", opts->scenario, "scenario YAML file (see scenarios/README.md)");
  sub->add_option("-o,--output", opts->output, "track file to write (CSV, odotune-track/1)");
  sub->add_option("--seed", opts->seed, "noise seed (integer); overrides the scenario's seed");
  sub->add_option("--effect", opts->effects,
                  "NAME:param=value,... switches on a physics effect or overrides its parameters "
                  "(repeatable; see --list-effects)")
      ->allow_extra_args(false);
  sub->add_option("--random-slip", opts->random_slip,
                  "replace the scenario's slip episodes with a random layout drawn with this seed (spin and hold, "
                  "either wheel, s 0.3-0.8, 2-5 s, only while moving): training drives for the slip detector");
  sub->add_flag("--no-effects", opts->no_effects, "ignore the effects of the scenario file");
  sub->add_flag("--list-effects", opts->list_effects, "print the effects, their parameters and ranges, and exit");
  sub->callback([opts] { run_simulate(*opts); });
}

}  // namespace odotune::cli

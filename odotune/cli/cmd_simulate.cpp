// `odotune simulate`: scenario YAML -> simulated track file.
//
//   odotune simulate SCENARIO.yaml -o TRACK.csv [--seed N]
//                    [--effect NAME:param=value,...]... [--no-effects]
//                    [--random-slip N]
//   odotune simulate --list-effects
//
// The overrides and the simulation are odotune/jobs/simulate_job.h; this file reads
// the flags, prints the effect table and the summary line.
#include <memory>
#include <string>

#include <fmt/format.h>

#include <odotune/cli/commands.h>
#include <odotune/core/failure.h>
#include <odotune/jobs/simulate_job.h>
#include <odotune/sim/effects.h>

namespace odotune::cli {

namespace {

void print_effect_table() {
  fmt::print("Effects (../shared/specs/physics-effects.md); use --effect NAME:param=value,...\n");
  for (const auto& e : sim::effect_table()) {
    fmt::print("  {}: {}\n", e.name, e.meaning);
    for (const auto& p : e.params)
      fmt::print("      {:<8} [{}] {}, range {}{}, {}]{}\n", p.name, p.unit, p.meaning,
                 p.min_exclusive ? "(" : "[", p.min, p.max,
                 p.required ? ", required" : fmt::format(", default {}", p.default_value));
  }
}

}  // namespace

void register_simulate(CLI::App& app) {
  auto req = std::make_shared<jobs::SimulateRequest>();
  auto list_effects = std::make_shared<bool>(false);
  auto* sub = app.add_subcommand(
      "simulate",
      "Simulate a differential-drive robot from a YAML scenario and write a track (odotune-track/1).\n"
      "Example: odotune simulate scenarios/track1.yaml -o track1.csv --seed 7 "
      "--effect lateral_skid:k=0.02 --effect radius_error:scale_l=0.995,scale_r=1.004");
  sub->add_option("scenario", req->scenario, "scenario YAML file (see scenarios/README.md)");
  sub->add_option("-o,--output", req->output, "track file to write (CSV, odotune-track/1)");
  sub->add_option("--seed", req->seed, "noise seed (integer); overrides the scenario's seed");
  sub->add_option("--effect", req->effects,
                  "NAME:param=value,... switches on a physics effect or overrides its parameters "
                  "(repeatable; see --list-effects)")
      ->allow_extra_args(false);
  sub->add_option(
      "--random-slip", req->random_slip,
      "replace the scenario's slip episodes with a random layout drawn with this seed (spin and hold, "
      "either wheel, s 0.3-0.8, 2-5 s, only while moving): training drives for the slip detector");
  sub->add_flag("--no-effects", req->no_effects, "ignore the effects of the scenario file");
  sub->add_flag("--list-effects", *list_effects, "print the effects, their parameters and ranges, and exit");
  sub->callback([req, list_effects] {
    if (*list_effects) return print_effect_table();
    const char* const usage = "expected: odotune simulate SCENARIO.yaml -o TRACK.csv";
    if (req->scenario.empty()) throw core::Failure(fmt::format("simulate: missing SCENARIO.yaml; {}", usage));
    if (req->output.empty()) throw core::Failure(fmt::format("simulate: missing -o TRACK.csv; {}", usage));
    const jobs::SimulateOutcome o = jobs::run_simulate(*req);
    fmt::print("wrote {}: track '{}', {} rows over {:.1f} s, path {:.1f} m, seed {}, effects: {}", req->output,
               o.track_name, o.rows, o.duration_s, o.path_length_m, o.seed, o.effects);
    if (o.slip_episodes > 0)
      fmt::print(", {} slip episode{}{}", o.slip_episodes, o.slip_episodes == 1 ? "" : "s",
                 req->random_slip.empty() ? "" : fmt::format(" (random layout {})", req->random_slip));
    fmt::print("\n");
  });
}

}  // namespace odotune::cli

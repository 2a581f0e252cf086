// odotune diagnose: where a nominal robot model and a recording disagree,
// which physics of ../shared/specs/physics-effects.md was left out, its
// fitted size, and the held-out proof (diagnose/diagnosis.h).
#include <filesystem>

#include <fmt/format.h>

#include "cli/commands.h"
#include "jobs/diagnosis_figure_data.h"
#include "formats/diagnosis_json.h"
#include "diagnose/diagnosis_summary.h"
#include "core/failure.h"
#include "cli/output.h"
#include "tracks/track_io.h"
#include "diagnose/diag_input.h"
#include "diagnose/diagnosis.h"
#include "formats/scenario_yaml.h"
#include "results/diagnosis_report.h"
#include "tracks/scenario_from_track.h"
#include "tracks/atomic_file.h"

namespace odotune::cli {
namespace {

struct DiagnoseArgs {
  std::string track;
  std::string json;
  std::string report;
  std::string scenario_out;
  double window_s = 20.0;
  double from_s = -1e300, to_s = 1e300;
};

void run_diagnose(const DiagnoseArgs& a) {
  const Track track = load_tracks({a.track}).front();
  diagnose::DiagInput in;
  try {
    in = diagnose::build_diag_input(track);
    if (a.from_s > -1e300 || a.to_s < 1e300) in = diagnose::crop(in, a.from_s, a.to_s);
  } catch (const std::invalid_argument& e) {
    throw Failure(fmt::format("{}: {}", a.track, e.what()));
  }
  diagnose::DiagnoseOptions o;
  o.select.fit.window_s = a.window_s;
  diagnose::Diagnosis d;
  try {
    d = diagnose::diagnose(in, o);
  } catch (const std::invalid_argument& e) {
    throw Failure(fmt::format("{}: cannot diagnose: {}", a.track, e.what()));
  }
  const std::vector<std::string> lines = diagnosis_summary(d);
  const std::string json_text = diagnosis_json(d).dump(2) + "\n";
  if (!a.report.empty()) {
    std::string finding;  // the effects' names (the titles have room for no more)
    for (const diagnose::Finding& f : d.findings) finding += (finding.empty() ? "" : ", ") + f.effect;
    try {
      results::write_diagnosis_report(a.report, diagnosis_figure_data(in, d, finding), lines, json_text);
    } catch (const std::exception& e) {
      throw Failure(fmt::format("{}: report: {}", a.report, e.what()));
    }
  }
  if (!a.scenario_out.empty()) {
    std::vector<std::string> specs;
    std::string names;
    for (const diagnose::Finding& f : d.findings)
      if (!f.spec().empty()) specs.push_back(f.spec()), names += (names.empty() ? "" : ", ") + f.effect;
    std::string yaml;
    try {
      const sim::Scenario sc = sim::scenario_from_track(track, specs);
      yaml = scenario_to_yaml(
          sc, fmt::format("The robot of track '{}' ({}) with the physics `odotune diagnose` found:\n"
                          "  {}\n"
                          "driven along the recording's reference path (motion.knots: its body\n"
                          "velocities, smoothed; simulated time 0 = the first reference sample).\n"
                          "Reproduce the corrected model:  odotune simulate THIS_FILE -o corrected.csv",
                          d.track, a.track, names.empty() ? "none (the nominal model explains it)" : names));
    } catch (const std::exception& e) {
      throw Failure(fmt::format("{}: cannot build the corrected scenario: {}", a.track, e.what()));
    }
    write_atomically(a.scenario_out, "scenario", yaml);
  }
  if (!a.json.empty()) write_atomically(a.json, "diagnosis JSON", json_text);
  for (const std::string& l : lines) fmt::print("{}\n", l);
  if (!a.json.empty()) fmt::print("json: {}\n", a.json);
  if (!a.scenario_out.empty()) fmt::print("scenario: {} (odotune simulate {} -o corrected.csv)\n", a.scenario_out, a.scenario_out);
  if (!a.report.empty()) fmt::print("report: {}\n", (std::filesystem::path(a.report) / "index.html").string());
}

}  // namespace

void register_diagnose(CLI::App& app) {
  auto args = std::make_shared<DiagnoseArgs>();
  auto* sub = app.add_subcommand(
      "diagnose", "Where the nominal model and a recording disagree, which physics was left out, and proof");
  sub->footer(
      "Example:\n"
      "  odotune simulate scenarios/track2.yaml -o /tmp/t2.csv --effect lateral_skid:k=0.04\n"
      "  odotune diagnose /tmp/t2.csv --json /tmp/t2-diagnosis.json\n"
      "The first line of the output says what was left out, its fitted size with uncertainty and\n"
      "the held-out improvement. The JSON follows ../shared/specs/diagnosis-output.md.");
  sub->add_option("track", args->track, "track file (track-format.md)")->required();
  sub->add_option("--json", args->json, "write the diagnosis as JSON (diagnosis-output.md)");
  sub->add_option("--report", args->report,
                  "folder for the figures (residual vs time and condition, map, overlay) and index.html");
  sub->add_option("--scenario-out", args->scenario_out,
                  "write the robot with the fitted effects as a simulator scenario (odotune simulate reads it)");
  sub->add_option("--from", args->from_s, "diagnose only the samples from this track time on [s]");
  sub->add_option("--to", args->to_s, "diagnose only the samples up to this track time [s]");
  sub->add_option("--window", args->window_s, "replay window [s]; the odometry is re-anchored on the reference at each")
      ->default_val(20.0)
      ->check(CLI::PositiveNumber);
  sub->callback([args] { run_diagnose(*args); });
}

}  // namespace odotune::cli

// odotune diagnose: where a nominal robot model and a recording disagree,
// which physics of ../shared/specs/physics-effects.md was left out, its
// fitted size, and the held-out proof (odotune/jobs/diagnose_job.h).
#include <filesystem>

#include <fmt/format.h>

#include <odotune/cli/commands.h>
#include <odotune/cli/controller_options.h>
#include <odotune/cli/output.h>
#include <odotune/jobs/diagnose_job.h>

namespace odotune::cli {

void register_diagnose(CLI::App& app) {
  auto req = std::make_shared<jobs::DiagnoseRequest>();
  auto* sub = app.add_subcommand(
      "diagnose", "Where the nominal model and a recording disagree, which physics was left out, and proof");
  sub->footer("Example:\n"
              "  odotune simulate scenarios/track2.yaml -o /tmp/t2.csv --effect lateral_skid:k=0.04\n"
              "  odotune diagnose /tmp/t2.csv --json /tmp/t2-diagnosis.json\n"
              "The first line of the output says what was left out, its fitted size with uncertainty and\n"
              "the held-out improvement. The JSON follows ../shared/specs/diagnosis-output.md.\n"
              "Several recordings of one robot:  odotune diagnose A.csv B.csv --heldout C.csv --json all.json\n"
              "(fitted on A and B pooled, proven on C; one JSON document with a `tracks` list).");
  sub->add_option("tracks", req->tracks,
                  "track file(s) (track-format.md); several recordings of one robot are fitted pooled")
      ->required();
  sub->add_option("--heldout", req->heldout,
                  "recordings of the same robot to prove the findings on (never fitted); repeatable");
  sub->add_option("--json", req->json, "write the diagnosis as JSON (diagnosis-output.md)");
  sub->add_option("--report", req->report,
                  "folder for the figures (residual vs time and condition, map, overlay) and index.html");
  sub->add_option(
      "--scenario-out", req->scenario_out,
      "write the robot with the fitted effects as a simulator scenario (odotune simulate reads it)");
  sub->add_option("--from", req->from_s, "diagnose only the samples from this track time on [s]");
  sub->add_option("--to", req->to_s, "diagnose only the samples up to this track time [s]");
  sub->add_option("--window", req->window_s,
                  "replay window [s]; the odometry is re-anchored on the reference at each")
      ->default_val(20.0)
      ->check(CLI::PositiveNumber);
  sub->add_option("--min-gain-sigmas", req->materiality.min_gain_sigmas,
                  "a finding's held-out gain must reach this many reference sigmas (materiality floor)")
      ->default_val(req->materiality.min_gain_sigmas)
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--min-gain-share", req->materiality.min_gain_share,
                  "... and this share of the nominal model's held-out error (the larger of the two)")
      ->default_val(req->materiality.min_gain_share)
      ->check(CLI::Range(0.0, 1.0));
  add_controller_options(sub, req->controller, false);
  sub->callback([req] {
    const jobs::DiagnoseRequest& a = *req;
    const jobs::DiagnoseOutcome o = jobs::run_diagnose(a);
    print_lines(o.summary);
    if (!a.json.empty()) fmt::print("json: {}\n", a.json);
    if (!a.scenario_out.empty())
      fmt::print("scenario: {} (odotune simulate {} -o corrected.csv)\n", a.scenario_out, a.scenario_out);
    if (!o.controller_line.empty()) fmt::print("{}\n", o.controller_line);
    if (!a.report.empty())
      fmt::print("report: {}\n", (std::filesystem::path(a.report) / "index.html").string());
  });
}

}  // namespace odotune::cli

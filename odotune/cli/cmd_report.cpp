// odotune report: the figures, tables and HTML page of a results store.
#include <fmt/format.h>

#include <odotune/cli/commands.h>
#include <odotune/cli/output.h>
#include <odotune/jobs/report_job.h>

namespace odotune::cli {

void register_report(CLI::App& app) {
  auto req = std::make_shared<jobs::ReportRequest>();
  auto* sub = app.add_subcommand(
      "report", "Heatmaps, boxplots, Table 1, trajectories, convergence and one HTML page from a store");
  sub->footer("Example:\n"
              "  odotune grid experiments/smoke.yaml\n"
              "  odotune report out/smoke.sqlite --out out/smoke-report     # then open index.html\n"
              "The store may still be growing: the report shows the runs finished so far.");
  sub->add_option("store", req->store, "results store written by odotune grid")->required();
  sub->add_option("--out", req->out_dir, "folder for the figures, tables and index.html")->required();
  sub->add_option("--track-name", req->trajectory_track,
                  "draw the trajectory overlay for this track only (default: every track)");
  add_fitness_mode_option(
      sub, [req](objectives::FitnessMode m) { req->mode = m; },
      "fitness mode of the trajectory and convergence figures, number or name")
      ->default_str("7");
  sub->add_option("--track", req->track_files,
                  "track file to use instead of the experiment's (if its files have moved)");
  sub->callback([req] {
    const jobs::ReportOutcome o = jobs::write_report(*req);
    fmt::print("{}: {} runs ({} leave-one-track-out) → {} files in {}\n", o.experiment, o.runs, o.heldout_runs,
               o.files.size(), req->out_dir.string());
    fmt::print("{}\n", o.headline);
    for (const auto& n : o.notes) fmt::print("note: {}\n", n);
    fmt::print("open {}\n", (req->out_dir / "index.html").string());
  });
}

}  // namespace odotune::cli

// odotune export: the best run of a results store as an odotune or
// robot_localization configuration (odotune/jobs/export_job.h selects and writes).
#include <fmt/format.h>

#include <odotune/cli/choices.h>
#include <odotune/cli/commands.h>
#include <odotune/jobs/export_job.h>

namespace odotune::cli {

void register_export(CLI::App& app) {
  auto req = std::make_shared<jobs::ExportRequest>();
  auto* sub = app.add_subcommand(
      "export", "Write the best run of a results store as an odotune or robot_localization configuration");
  sub->footer(
      "Example:\n"
      "  odotune grid experiments/smoke.yaml --store out/smoke.sqlite\n"
      "  odotune export out/smoke.sqlite --select model=alpha,track=track1 --format odotune --out alpha.yaml\n"
      "  odotune eval --config alpha.yaml --track data/tracks/track1.csv\n"
      "  odotune export out/smoke.sqlite --select model=rq --select mode=7 --format robot_localization \\\n"
      "      --out ekf.yaml\n"
      "--select keys: model, track (e.g. track1, or all-but-track1 for leave-one-out runs), mode,\n"
      "seed, heldout (the held-out track of a leave-one-out run, or none). They must leave runs of\n"
      "one model; of those the run with the lowest tuned RMSE on its scored track is exported.\n"
      "robot_localization needs the run's track(s) for the odometry rate and, for alpha/gyro, the\n"
      "time-averaged process noise (see the file's comments); --track supplies moved files.\n"
      "An rl-ekf run (robot_localization's own EKF, experiments/rl_smoke.yaml) is written as the robot's\n"
      "parameter file with the tuned values; its runs must be of one fitness (--select mode=8|10|11) and\n"
      "the lowest tuning fitness wins, since their scores are on data the tune never saw.");
  sub->add_option("store", req->store, "results store written by odotune grid")->required();
  sub->add_option_function<std::vector<std::string>>(
         "--select",
         [req](const std::vector<std::string>& items) { req->select = jobs::parse_run_filters(items); },
         "key=value filters, comma-separated or repeated; keys: model, track, mode, seed, heldout")
      ->delimiter(',');
  add_enum_option(sub, "--format", req->format, jobs::kAllExportFormats,
                  "odotune's own configuration file, or robot_localization's parameter file")
      ->required();
  sub->add_option("--out", req->out, "file to write (atomically)")->required();
  sub->add_option("--track", req->track_files,
                  "track file to use instead of the experiment's (if its files have moved)");
  sub->add_option("--node-name", req->node_name,
                  "robot_localization: the ekf node's name, the file's top-level key")
      ->default_val("ekf_filter_node");
  sub->add_flag("--ros1", req->ros1, "rl-ekf runs: write the ROS 1 form of the robot's file (default ROS 2)");
  sub->callback([req] {
    const jobs::ExportOutcome o = jobs::run_export(*req);
    fmt::print("exported run {} ({}; best of {} matching run{}) as {} to {}\n", o.run_key, o.scores, o.matching,
               o.matching == 1 ? "" : "s", jobs::to_string(req->format), req->out);
  });
}

}  // namespace odotune::cli

// odotune eval: replay a configuration (or the baseline) over tracks
// (odotune/jobs/eval_job.h).
#include <fmt/format.h>

#include <odotune/cli/commands.h>
#include <odotune/cli/output.h>
#include <odotune/cli/rl_output.h>
#include <odotune/core/failure.h>
#include <odotune/jobs/eval_job.h>
#include <odotune/jobs/rl_job.h>

namespace odotune::cli {
namespace {

// The robot_localization flags given (by their help groups, rl_output.h)
// where they do not apply: without --rl-params, a track's on a bag and a
// bag's on tracks; each refused by name. `rl_on_tracks`: --rl-params with
// --track and no --bag.
void check_eval_flags(const CLI::App& sub, bool rl, bool rl_on_tracks) {
  for (const CLI::Option* opt : given_options(sub)) {
    const std::string& name = opt->get_name();
    const std::string& group = opt->get_group();
    if (group == kRlTrackGroup && !rl_on_tracks)
      throw core::Failure(fmt::format("eval: {} applies to --rl-params with --track only", name));
    if (!rl && (group == kRlGroup || group == kRlBagGroup))
      throw core::Failure(fmt::format("eval: {} applies to --rl-params only", name));
    if (rl_on_tracks && (group == kRlBagGroup || name == "--config"))
      throw core::Failure(fmt::format("eval: {} applies to --rl-params with --bag, not with --track", name));
  }
}

}  // namespace

void register_eval(CLI::App& app) {
  auto req = std::make_shared<jobs::EvalRequest>();
  auto* sub = app.add_subcommand("eval", "Replay the EKF with a configuration and report its errors");
  sub->footer(
      "Example:\n"
      "  odotune tune --track data/tracks/track2.csv --model alpha --config-out alpha.yaml\n"
      "  odotune eval --config alpha.yaml --track data/tracks/track3.csv\n"
      "  odotune eval --config alpha.yaml --track husky.csv --trajectory-out husky.tum   # evo_traj tum husky.tum\n"
      "Without --config the baseline configuration is evaluated. A track without ground truth is scored by\n"
      "its held-out position fixes (5 folds of 1 s blocks, as tune's mode 8).\n"
      "robot_localization's EKF as the robot runs it, from its own bag and parameter file:\n"
      "  odotune eval --rl-params husky_ekf.yaml --bag test1.bag --tf imu_link=0,-0.3,0.52,1.5707963,0,-1.5707963 \\\n"
      "      --gps-heading-fit 60 --from 197.6 --trajectory-out husky.tum\n"
      "  prints the final pose and the held-out fix errors (docs/husky.md).\n"
      "robot_localization's EKF on tracks (odometry as odomN, gyro_z as imuN, the fixes as a pose input;\n"
      "docs/robot-localization.md):\n"
      "  odotune eval --rl-params user.yaml --track robot3-fixes.csv --trajectory-out robot3.tum\n"
      "  prints the RMSE against the track's ground truth with every fix fused and through simulated fix\n"
      "  outages, and the held-out fix errors a user without ground truth would see.");
  sub->add_option("--config", req->config, "configuration YAML (format odotune-ekf-config/1)");
  sub->add_option("--track", req->tracks, "track file (repeat for several)");
  sub->add_option("--json", req->json_out, "write the metrics as JSON to this file");
  sub->add_option(
      "--trajectory-out", req->trajectory_out,
      "write the filter's trajectory in TUM format (t x y z qx qy qz qw; evo reads it); one track; with "
      "--rl-params and --from, the run with GPS fused before --from only");
  auto rl = std::make_shared<jobs::RlEvalRequest>();
  add_rl_source_options(sub, rl->src);
  sub->add_option("--until", rl->until_s, "--rl-params: use the recording before this many seconds")
      ->check(CLI::PositiveNumber)
      ->group(kRlBagGroup);
  sub->add_option("--from", rl->from_s,
                  "--rl-params: score from this many seconds on: a GPS outage from there, and every 5th fix "
                  "held out from there")
      ->check(CLI::NonNegativeNumber)
      ->group(kRlBagGroup);
  sub->add_option("--noise-from", rl->noise_from,
                  "--rl-params: take process_noise_covariance from this robot_localization file instead")
      ->check(CLI::ExistingFile)
      ->group(kRlGroup);
  auto keys_only = std::make_shared<bool>(false);
  sub->add_flag("--keys", *keys_only,
                "--rl-params: list what the replay makes of each key of the file (reproduced, no effect, not "
                "read, approximated) and stop; no bag needed")
      ->group(kRlGroup);
  sub->add_option("--fixes-out", rl->fixes_out, "--rl-params: write the GPS fixes in the odom frame (t x y)")
      ->group(kRlBagGroup);
  sub->add_option("--outages", rl->outages_s,
                  "--rl-params: also simulate GPS outages of these lengths [s] (comma-separated), one of each "
                  "starting every --outage-every seconds from --from (or 30 s after the first fix), the GPS "
                  "fused before each; prints their RMSE")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->group(kRlGroup);
  sub->add_option("--outage-every", rl->outage_every_s,
                  "--rl-params: with --outages, their stride [s] (default 10)")
      ->check(CLI::PositiveNumber)
      ->group(kRlGroup);
  auto track_src = std::make_shared<jobs::RlTrackSource>();
  add_rl_track_options(sub, *track_src);
  sub->callback([req, rl, track_src, sub, keys_only] {
    if (*keys_only) {
      if (rl->src.params_file.empty())
        throw core::Failure("eval: --keys lists the keys of an --rl-params file; expected one");
      print_rl_keys(jobs::read_rl_file(rl->src));
      return;
    }
    const bool rl_on_tracks = !rl->src.params_file.empty() && rl->src.bag.empty() && !req->tracks.empty();
    check_eval_flags(*sub, !rl->src.params_file.empty(), rl_on_tracks);
    if (rl_on_tracks) {
      jobs::RlTrackEvalRequest t;
      t.src = *track_src;
      t.src.params_file = rl->src.params_file;
      t.src.node_name = rl->src.node_name;
      t.src.filter = rl->src.filter;
      t.src.tracks = {req->tracks.begin(), req->tracks.end()};
      t.noise_from = rl->noise_from;
      if (!rl->outages_s.empty()) t.protocols.outage_s = rl->outages_s;
      t.protocols.outage_stride_s = rl->outage_every_s;
      t.trajectory_out = req->trajectory_out;
      t.json_out = req->json_out;
      print_rl_track_eval(jobs::run_rl_track_eval(t));
      return;
    }
    if (!rl->src.params_file.empty()) {
      if (!req->tracks.empty() || !req->config.empty())
        throw core::Failure(
            "eval: --rl-params replays a bag or tracks; expected --bag or --track, not both, and no --config");
      rl->trajectory_out = req->trajectory_out;
      rl->json_out = req->json_out;
      print_rl_eval(jobs::run_rl_eval(*rl));
      return;
    }
    if (req->tracks.empty())
      throw core::Failure("eval: expected --track, or --rl-params with --bag or --track");
    jobs::run_eval(*req, [&](const jobs::EvalOutcome& o) {
      const jobs::EvalTrack& t = o.tracks.back();
      const objectives::ErrorMetrics& m = t.metrics;
      fmt::print("{}: {} — {}RMSE {:.2f} mm, MAE {:.2f} mm, MAXE {:.2f} mm ({} samples){}\n", t.track, o.label,
                 t.against_fixes ? "held-out fixes (no ground truth): " : "", m.rmse_m * 1e3, m.mae_m * 1e3,
                 m.maxe_m * 1e3, m.samples,
                 t.divergence == filters::Divergence::none
                     ? ""
                     : fmt::format(", DIVERGED ({})", filters::to_string(t.divergence)));
      if (!req->config.empty())
        fmt::print("  vs baseline: RMSE {}\n", metric_change(t.baseline.rmse_m, m.rmse_m));
    });
  });
}

}  // namespace odotune::cli

// odotune eval: replay a configuration (or the baseline) over tracks
// (jobs/eval_job.h).
#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/output.h"
#include "jobs/eval_job.h"

namespace odotune::cli {

void register_eval(CLI::App& app) {
  auto req = std::make_shared<EvalRequest>();
  auto* sub = app.add_subcommand("eval", "Replay the EKF with a configuration and report its errors");
  sub->footer(
      "Example:\n"
      "  odotune tune --track data/tracks/track2.csv --model alpha --config-out alpha.yaml\n"
      "  odotune eval --config alpha.yaml --track data/tracks/track3.csv\n"
      "  odotune eval --config alpha.yaml --track husky.csv --trajectory-out husky.tum   # evo_traj tum husky.tum\n"
      "Without --config the baseline configuration is evaluated. A track without ground truth is scored by\n"
      "its held-out position fixes (5 folds of 1 s blocks, as tune's mode 8).");
  sub->add_option("--config", req->config, "configuration YAML (format odotune-ekf-config/1)");
  sub->add_option("--track", req->tracks, "track file (repeat for several)")->required();
  sub->add_option("--json", req->json_out, "write the metrics as JSON to this file");
  sub->add_option("--trajectory-out", req->trajectory_out,
                  "write the filter's trajectory in TUM format (t x y z qx qy qz qw; evo reads it); one track");
  sub->callback([req] {
    run_eval(*req, [&](const EvalOutcome& o) {
      const EvalTrack& t = o.tracks.back();
      const ErrorMetrics& m = t.metrics;
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

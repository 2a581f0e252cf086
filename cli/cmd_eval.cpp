// odotune eval: replay a configuration (or the baseline) over tracks.
#include <fmt/format.h>

#include "cli/commands.h"
#include "formats/config_yaml.h"
#include "core/failure.h"
#include "cli/output.h"
#include "tracks/track_io.h"
#include "jobs/tune_json.h"
#include "objectives/param_space.h"
#include "objectives/replay.h"

namespace odotune::cli {

namespace {
struct EvalArgs {
  std::string config;
  std::vector<std::string> tracks;
  std::string json_out;
};
}  // namespace

void register_eval(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  auto* sub = app.add_subcommand("eval", "Replay the EKF with a configuration and report its errors");
  sub->footer(
      "Example:\n"
      "  odotune tune --track data/tracks/track2.csv --model alpha --config-out alpha.yaml\n"
      "  odotune eval --config alpha.yaml --track data/tracks/track3.csv\n"
      "Without --config the baseline configuration is evaluated.");
  sub->add_option("--config", args->config, "configuration YAML (format odotune-ekf-config/1)");
  sub->add_option("--track", args->tracks, "track file (repeat for several)")->required();
  sub->add_option("--json", args->json_out, "write the metrics as JSON to this file");
  sub->callback([args] {
    filters::NoiseParams noise = baseline_noise();
    std::string label = "baseline";
    if (!args->config.empty()) {
      noise = read_ekf_config(args->config).noise;
      label = args->config;
    }
    nlohmann::json j;
    j["config"] = label;
    j["model"] = std::string(filters::to_string(noise.model));
    nlohmann::json per_track = nlohmann::json::array();
    for (const auto& track : load_tracks(args->tracks)) {
      ReplayInput in;
      try {
        in = build_replay_input(track);
      } catch (const std::invalid_argument& e) {
        throw Failure(e.what());
      }
      const ReplayResult base = replay_ekf(in, baseline_noise());
      const ReplayResult got = replay_ekf(in, noise);
      const auto& m = got.outcome.metrics;
      fmt::print("{}: {} — RMSE {:.2f} mm, MAE {:.2f} mm, MAXE {:.2f} mm ({} samples){}\n",
                 track.name(), label, m.rmse_m * 1e3, m.mae_m * 1e3, m.maxe_m * 1e3, m.samples,
                 got.outcome.divergence == filters::Divergence::none
                     ? ""
                     : fmt::format(", DIVERGED ({})", filters::to_string(got.outcome.divergence)));
      if (!args->config.empty())
        fmt::print("  vs baseline: RMSE {}\n",
                   metric_change(base.outcome.metrics.rmse_m, m.rmse_m));
      per_track.push_back({{"track", track.name()},
                           {"metrics", metrics_json(m)},
                           {"baseline", metrics_json(base.outcome.metrics)},
                           {"divergence", std::string(filters::to_string(got.outcome.divergence))}});
    }
    j["tracks"] = per_track;
    if (!args->json_out.empty()) write_file_atomically(args->json_out, j.dump(2) + "\n");
  });
}

}  // namespace odotune::cli

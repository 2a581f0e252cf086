#include "jobs/eval_job.h"

#include <stdexcept>

#include "core/failure.h"
#include "formats/config_yaml.h"
#include "jobs/tune_json.h"
#include "objectives/param_space.h"
#include "objectives/replay.h"
#include "tracks/track_io.h"

namespace odotune {

nlohmann::json eval_json(const EvalOutcome& o) {
  nlohmann::json j;
  j["config"] = o.label;
  j["model"] = std::string(filters::to_string(o.model));
  nlohmann::json per_track = nlohmann::json::array();
  for (const EvalTrack& t : o.tracks)
    per_track.push_back({{"track", t.track},
                         {"metrics", metrics_json(t.metrics)},
                         {"baseline", metrics_json(t.baseline)},
                         {"divergence", std::string(filters::to_string(t.divergence))}});
  j["tracks"] = per_track;
  return j;
}

EvalOutcome run_eval(const EvalRequest& request, const std::function<void(const EvalOutcome&)>& track_done) {
  filters::NoiseParams noise = baseline_noise();
  EvalOutcome o;
  o.label = "baseline";
  if (!request.config.empty()) {
    noise = read_ekf_config(request.config).noise;
    o.label = request.config;
  }
  o.model = noise.model;
  for (const auto& track : load_tracks(request.tracks)) {
    ReplayInput in;
    try {
      in = build_replay_input(track);
    } catch (const std::invalid_argument& e) {
      throw Failure(e.what());
    }
    const ReplayResult base = replay_ekf(in, baseline_noise());
    const ReplayResult got = replay_ekf(in, noise);
    o.tracks.push_back({track.name(), got.outcome.metrics, base.outcome.metrics, got.outcome.divergence});
    if (track_done) track_done(o);
  }
  if (!request.json_out.empty()) write_file_atomically(request.json_out, eval_json(o).dump(2) + "\n");
  return o;
}

}  // namespace odotune

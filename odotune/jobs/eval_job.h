// `odotune eval`: the EKF replayed on tracks with a tuned configuration (or
// the baseline noise), its position errors beside the baseline's, and their
// JSON. Computation and file output only; the command prints.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <odotune/filters/ekf.h>
#include <odotune/filters/ekf_noise.h>
#include <odotune/objectives/metrics.h>

namespace odotune::jobs {

struct EvalRequest {
  std::string config;               // odotune-ekf-config/1 YAML; empty = the baseline noise
  std::vector<std::string> tracks;  // track files, replayed in this order
  std::string json_out;             // the metrics as JSON (eval_json); empty = not written
  // The configured filter's trajectory in TUM format (odotune/results/tum.h), one
  // track only; on the recording's clock when the track has source.t0_ns.
  std::string trajectory_out;
};

struct EvalTrack {
  std::string track;                  // the track's name
  objectives::ErrorMetrics metrics;   // with the configuration's noise
  objectives::ErrorMetrics baseline;  // with baseline_noise()
  // A track without ground truth: the metrics are of its held-out fixes
  // (odotune/objectives/fix_cv_replay.h, default folds), not of ground truth.
  bool against_fixes = false;
  filters::Divergence divergence = filters::Divergence::none;  // of the configuration's replay
};

struct EvalOutcome {
  std::string label;                                       // "baseline", or the configuration's path
  filters::NoiseModel model = filters::NoiseModel::alpha;  // the configuration's noise model
  std::vector<EvalTrack> tracks;                           // in request order
};

// {"config": label, "model", "tracks": [{"track", "metrics", "baseline",
// "divergence"}]} (metrics as odotune/jobs/tune_json.h's metrics_json).
nlohmann::json eval_json(const EvalOutcome& o);

// Reads the configuration and all tracks, then replays each track with the
// baseline and the configuration's noise; `track_done` (if set) is told the
// outcome so far after each track (the one just replayed last). Writes the
// JSON last, atomically. Throws core::Failure (one line) on an unreadable
// configuration or track, a track that cannot be replayed, or an unwritable
// JSON file.
EvalOutcome run_eval(const EvalRequest& request,
                     const std::function<void(const EvalOutcome&)>& track_done = {});

}  // namespace odotune::jobs

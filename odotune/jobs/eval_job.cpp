#include <odotune/jobs/eval_job.h>

#include <odotune/objectives/fix_cv_replay.h>
#include <odotune/results/tum.h>

#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/formats/config_yaml.h>
#include <odotune/jobs/tune_json.h>
#include <odotune/objectives/param_space.h>
#include <odotune/objectives/replay.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

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
  filters::NoiseParams noise = objectives::baseline_noise();
  EvalOutcome o;
  o.label = "baseline";
  if (!request.config.empty()) {
    noise = formats::read_ekf_config(request.config).noise;
    o.label = request.config;
  }
  o.model = noise.model;
  const std::vector<tracks::Track> tracks = tracks::load_tracks(request.tracks);
  if (!request.trajectory_out.empty() && tracks.size() != 1)
    throw core::Failure("--trajectory-out writes one track's trajectory: give exactly one --track");
  for (const auto& track : tracks) {
    objectives::ReplayInput in;
    EvalTrack et;
    et.track = track.name();
    try {
      if (track.has_gt()) {
        in = objectives::build_replay_input(track);
        const objectives::ReplayResult base = objectives::replay_ekf(in, objectives::baseline_noise());
        const objectives::ReplayResult got = objectives::replay_ekf(in, noise);
        et.metrics = got.outcome.metrics;
        et.baseline = base.outcome.metrics;
        et.divergence = got.outcome.divergence;
      } else {
        objectives::ReplayInputOptions from_fix;
        from_fix.reference = objectives::ReplayReference::fixes;
        in = objectives::build_replay_input(track, from_fix);
        const objectives::FixCvReplay cv(in, {});
        const objectives::FixCvOutcome got = cv.evaluate(noise);
        et.metrics = got.heldout;
        et.baseline = cv.evaluate(objectives::baseline_noise()).heldout;
        et.divergence = got.divergence;
        et.against_fixes = true;
      }
    } catch (const std::invalid_argument& e) {
      throw core::Failure(e.what());
    }
    o.tracks.push_back(et);
    if (!request.trajectory_out.empty()) {
      const auto t0 = track.meta().get("source.t0_ns");
      const double offset_s = t0 ? std::stod(*t0) * 1e-9 : 0.0;
      results::write_tum(request.trajectory_out, objectives::ekf_trajectory(in, noise),
                         fmt::format("odotune eval: EKF {} on track '{}' ({}); {}", o.label, track.name(),
                                     filters::to_string(noise.model),
                                     in.reference_is_fixes ? in.initial_pose_note
                                                           : "at the first ground-truth pose"),
                         offset_s);
    }
    if (track_done) track_done(o);
  }
  if (!request.json_out.empty()) formats::write_file_atomically(request.json_out, eval_json(o).dump(2) + "\n");
  return o;
}

}  // namespace odotune::jobs

#include <odotune/jobs/ukf_tune_json.h>

#include <fmt/format.h>

#include <odotune/jobs/tune_json.h>

namespace odotune::jobs {

nlohmann::json ukf_tune_json(const UkfTuneOutcome& o, double fusion_rate_hz) {
  const UkfTuneRequest& r = o.request;
  nlohmann::json j;
  j["model"] = "ukf";
  j["mode"] = objectives::number(r.mode);
  j["mode_name"] = objectives::fitness_mode_name(r.mode);
  put_solver_json(j, r);
  j["fusion_rate_hz"] = fusion_rate_hz;
  put_tuned_params_json(j, o.param_names, o.param_units, o.params, o.default_params, o.default_kept);
  put_scores_json(j, o.baseline_mean, o.tuned_mean, o.baseline_fitness, o.tuned_fitness, o.summary);
  j["failures"] = o.failures;
  j["tracks"] = track_scores_json(o.tracks);
  return j;
}

}  // namespace odotune::jobs

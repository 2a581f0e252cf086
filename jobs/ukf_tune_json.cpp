#include "jobs/ukf_tune_json.h"

#include <fmt/format.h>

#include "jobs/tune_json.h"

namespace odotune {

nlohmann::json ukf_tune_json(const UkfTuneOutcome& o, double fusion_rate_hz) {
  const UkfTuneRequest& r = o.request;
  nlohmann::json j;
  j["model"] = "ukf";
  j["mode"] = r.mode;
  j["mode_name"] = fitness_mode_name(r.mode);
  j["solver"] = r.solver;
  j["seed"] = r.seed;
  if (r.solver == "pso") {
    j["particles"] = r.particles;
    j["iterations"] = r.iterations;
  }
  j["fusion_rate_hz"] = fusion_rate_hz;
  put_tuned_params_json(j, o.param_names, o.param_units, o.params, o.default_params, o.default_kept);
  j["baseline"] = metrics_json(o.baseline_mean);
  j["tuned"] = metrics_json(o.tuned_mean);
  j["improvement_pct"] = improvement_json(o.baseline_mean, o.tuned_mean);
  j["baseline_fitness"] = o.baseline_fitness;
  j["tuned_fitness"] = o.tuned_fitness;
  j["evaluations"] = o.summary.evaluations;
  j["seconds"] = o.summary.seconds;
  j["termination"] = o.summary.termination;
  j["failures"] = o.failures;
  j["tracks"] = track_scores_json(o.tracks);
  j["convergence"] = convergence_json(o.summary);
  return j;
}

}  // namespace odotune

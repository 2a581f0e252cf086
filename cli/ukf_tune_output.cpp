#include "cli/ukf_tune_output.h"

#include <fmt/format.h>

#include "cli/output.h"

namespace odotune::cli {

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

void print_ukf_outcome(const UkfTuneOutcome& o) {
  const UkfTuneRequest& r = o.request;
  std::string names;
  for (const auto& t : o.tracks) names += (names.empty() ? "" : ", ") + t.track;
  fmt::print("tuned the fusion UKF's noise on {} for mode {} ({}) with {} (seed {})\n", names, r.mode,
             fitness_mode_name(r.mode), r.solver, r.seed);
  fmt::print("  fused pose vs ground truth, defaults → tuned{}\n",
             o.default_kept ? " (the defaults scored best and are kept)" : "");
  print_tune_result(o.baseline_mean, o.tuned_mean, o.tracks, o.param_names, o.params, o.summary,
                    o.failures);
}

}  // namespace odotune::cli

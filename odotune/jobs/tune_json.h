// The JSON pieces of a tune's result (`tune --json`, the grid's stored runs):
// metrics, improvement, per-track scores, the solver's convergence log and the
// tuned parameters by name. The calibrator and UKF tunes add theirs in
// calibration_tune_json.h and ukf_tune_json.h.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <odotune/jobs/tune_job.h>
#include <odotune/objectives/metrics.h>
#include <odotune/tuner/summary.h>

namespace odotune::jobs {

nlohmann::json metrics_json(const objectives::ErrorMetrics& m);
// The --json document of `tune` (see README for the keys).
nlohmann::json tune_json(const TuneOutcome& o);

// The pieces every tune's --json shares (tune, the calibrator and UKF tunes):
// {"rmse", "mae", "maxe"} improvement in %, the per-track baseline/tuned
// metrics, and the solver's convergence log.
nlohmann::json improvement_json(const objectives::ErrorMetrics& baseline,
                                const objectives::ErrorMetrics& tuned);
nlohmann::json track_scores_json(const std::vector<TrackScore>& tracks);
nlohmann::json convergence_json(const tuner::Summary& summary);
// The solver of a tune, into j: "solver", "seed", and for PSO "particles" and
// "iterations".
void put_solver_json(nlohmann::json& j, const SolverSettings& s);
// What every tune scored, into j: "baseline" and "tuned" (mean position errors
// over the tracks), "improvement_pct", "baseline_fitness", "tuned_fitness", the
// solver's "evaluations", "seconds", "termination" and its "convergence" log.
void put_scores_json(nlohmann::json& j, const objectives::ErrorMetrics& baseline,
                     const objectives::ErrorMetrics& tuned, double baseline_fitness, double tuned_fitness,
                     const tuner::Summary& summary);
// The tuned and default values by parameter name, into j: "params",
// "param_units", "default_params" (each an object keyed by name) and
// "default_kept" (the calibrator and UKF tunes, which start from defaults).
void put_tuned_params_json(nlohmann::json& j, const std::vector<std::string>& names,
                           const std::vector<std::string>& units, const std::vector<double>& tuned,
                           const std::vector<double>& defaults, bool default_kept);

}  // namespace odotune::jobs

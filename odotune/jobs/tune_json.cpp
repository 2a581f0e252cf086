#include <odotune/jobs/tune_json.h>

namespace odotune::jobs {

nlohmann::json metrics_json(const objectives::ErrorMetrics& m) {
  return {{"rmse_m", m.rmse_m}, {"mae_m", m.mae_m}, {"maxe_m", m.maxe_m}, {"samples", m.samples}};
}

nlohmann::json tune_json(const TuneOutcome& o) {
  nlohmann::json j;
  j["model"] = std::string(filters::to_string(o.request.model));
  j["mode"] = objectives::number(o.request.mode);
  j["mode_name"] = objectives::fitness_mode_name(o.request.mode);
  put_solver_json(j, o.request);
  nlohmann::json params = nlohmann::json::object(), units = nlohmann::json::object();
  for (std::size_t i = 0; i < o.params.size(); ++i) {
    params[o.param_names[i]] = o.params[i];
    units[o.param_names[i]] = o.param_units[i];
  }
  j["params"] = params;
  j["param_units"] = units;
  put_scores_json(j, o.baseline_mean, o.tuned_mean, o.baseline_fitness, o.tuned_fitness, o.summary);
  j["divergences"] = {{"non_finite", o.divergences.non_finite},
                      {"covariance_not_pd", o.divergences.covariance_not_pd}};
  j["tracks"] = track_scores_json(o.tracks);
  j["scored_against"] = o.against_fixes ? "held-out position fixes" : "ground truth";
  if (o.against_fixes) {
    const objectives::FixCvOptions& cv = o.fix_cv;
    j["fix_cv"] = {{"folds", cv.folds}, {"block_s", cv.block_s}};
    for (std::size_t i = 0; i < o.tracks.size(); ++i) {
      const TrackScore& t = o.tracks[i];
      auto& jt = j["tracks"][i];
      jt["baseline_nll"] = t.baseline_nll;
      jt["tuned_nll"] = t.tuned_nll;
      jt["baseline_nis"] = t.baseline_nis;
      jt["tuned_nis"] = t.tuned_nis;
      if (t.gt_baseline && t.gt_tuned) {
        jt["ground_truth_baseline"] = metrics_json(*t.gt_baseline);
        jt["ground_truth_tuned"] = metrics_json(*t.gt_tuned);
      }
    }
  }
  if (!o.note.empty()) j["note"] = o.note;
  return j;
}

void put_solver_json(nlohmann::json& j, const SolverSettings& s) {
  j["solver"] = s.solver.name();
  j["seed"] = s.seed;
  if (s.solver.kind == tuner::SolverChoice::Kind::pso) {
    j["particles"] = s.particles;
    j["iterations"] = s.iterations;
  }
}

void put_scores_json(nlohmann::json& j, const objectives::ErrorMetrics& baseline,
                     const objectives::ErrorMetrics& tuned, double baseline_fitness, double tuned_fitness,
                     const tuner::Summary& summary) {
  j["baseline"] = metrics_json(baseline);
  j["tuned"] = metrics_json(tuned);
  j["improvement_pct"] = improvement_json(baseline, tuned);
  j["baseline_fitness"] = baseline_fitness;
  j["tuned_fitness"] = tuned_fitness;
  j["evaluations"] = summary.evaluations;
  j["seconds"] = summary.seconds;
  j["termination"] = summary.termination_text();
  j["convergence"] = convergence_json(summary);
}

void put_tuned_params_json(nlohmann::json& j, const std::vector<std::string>& names,
                           const std::vector<std::string>& units, const std::vector<double>& tuned,
                           const std::vector<double>& defaults, bool default_kept) {
  nlohmann::json params = nlohmann::json::object(), unit = nlohmann::json::object(),
                 start = nlohmann::json::object();
  for (std::size_t i = 0; i < tuned.size(); ++i) {
    params[names[i]] = tuned[i];
    unit[names[i]] = units[i];
    start[names[i]] = defaults[i];
  }
  j["params"] = params;
  j["param_units"] = unit;
  j["default_params"] = start;
  j["default_kept"] = default_kept;
}

nlohmann::json improvement_json(const objectives::ErrorMetrics& baseline,
                                const objectives::ErrorMetrics& tuned) {
  return {{"rmse", objectives::improvement_pct(baseline.rmse_m, tuned.rmse_m)},
          {"mae", objectives::improvement_pct(baseline.mae_m, tuned.mae_m)},
          {"maxe", objectives::improvement_pct(baseline.maxe_m, tuned.maxe_m)}};
}

nlohmann::json track_scores_json(const std::vector<TrackScore>& tracks) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& t : tracks)
    out.push_back(
        {{"track", t.track}, {"baseline", metrics_json(t.baseline)}, {"tuned", metrics_json(t.tuned)}});
  return out;
}

nlohmann::json convergence_json(const tuner::Summary& summary) {
  nlohmann::json log = nlohmann::json::array();
  for (const auto& r : summary.log)
    log.push_back(
        {{"iteration", r.iteration}, {"evaluations", r.evaluations}, {"best_fitness", r.best_fitness}});
  return log;
}

}  // namespace odotune::jobs

#include <odotune/jobs/calibration_tune_json.h>

#include <cmath>
#include <optional>

#include <fmt/format.h>

#include <odotune/jobs/tune_json.h>

namespace odotune::jobs {

namespace {

nlohmann::json side_json(const CalibrationTrackScore& s, double mean_particles) {
  nlohmann::json j = metrics_json(s.errors);
  const auto& p = s.calibration.final_params;
  j["final_params"] = {{"wheel_radius_left_m", p.wheel_radius_left_m},
                       {"wheel_radius_right_m", p.wheel_radius_right_m},
                       {"wheel_base_m", p.wheel_base_m}};
  j["convergence_time_s"] = s.calibration.convergence_time_s ? nlohmann::json(*s.calibration.convergence_time_s)
                                                             : nlohmann::json(nullptr);
  const auto e = radius_error_pct(s.calibration);
  j["radius_error_pct"] = e ? nlohmann::json(*e) : nlohmann::json(nullptr);
  j["mean_particles"] = mean_particles;
  return j;
}

// The particle count the calibrator runs with (calibration_run.h's rule for
// the adaptive PF's initial count applied).
int effective_particles(const filters::PfCalibratorParams& pf, objectives::CalibratorModel model) {
  calibration::CalibrationOptions o;
  o.method = calibration_method(model);
  o.pf = pf;
  return calibration::effective_pf_params(o).particles;
}

}  // namespace

std::optional<double> radius_error_pct(const calibration::TrackCalibrationScore& s) {
  if (!s.truth_final) return std::nullopt;
  const auto& e = s.final_params;
  const auto& t = *s.truth_final;
  return 50.0 * (std::abs(e.wheel_radius_left_m - t.wheel_radius_left_m) / t.wheel_radius_left_m +
                 std::abs(e.wheel_radius_right_m - t.wheel_radius_right_m) / t.wheel_radius_right_m);
}

std::string convergence_text(const calibration::TrackCalibrationScore& s) {
  if (!s.truth_final) return "no truth";
  return s.convergence_time_s ? fmt::format("converged at {:.1f} s", *s.convergence_time_s) : "never converged";
}

nlohmann::json calibration_tune_json(const CalibrationTuneOutcome& o, const CalibrationTuneContext& c) {
  const CalibrationTuneRequest& r = o.request;
  nlohmann::json j;
  j["model"] = objectives::to_string(objectives::TunedModel::calibration(r.model));
  put_solver_json(j, r);
  j["calibrator"] = {{"method", std::string(calibration::to_string(jobs::calibration_method(r.model)))},
                     {"resampler", std::string(filters::to_string(o.default_pf.resampler))},
                     {"policy", std::string(filters::to_string(o.default_pf.policy))},
                     {"particles", effective_particles(o.default_pf, r.model)},
                     {"seed", o.default_pf.seed},
                     {"ext_from_gt_hz", c.ext_from_gt_hz}};
  put_tuned_params_json(j, o.param_names, o.param_units, o.params, o.default_params, o.default_kept);
  j["score_weights"] = {{"radius", r.weights.radius},
                        {"convergence", r.weights.convergence},
                        {"pose", r.weights.pose},
                        {"cost", r.weights.cost}};
  j["baseline_score"] = o.baseline_score;
  j["tuned_score"] = o.tuned_score;
  put_scores_json(j, o.baseline_mean, o.tuned_mean, o.baseline_score, o.tuned_score, o.summary);
  j["failures"] = o.failures;
  nlohmann::json tracks = nlohmann::json::array();
  for (std::size_t k = 0; k < o.baseline.tracks.size() && k < o.tuned.tracks.size(); ++k)
    tracks.push_back({{"track", o.baseline.tracks[k].track},
                      {"baseline", side_json(o.baseline.tracks[k], o.baseline.mean_particles)},
                      {"tuned", side_json(o.tuned.tracks[k], o.tuned.mean_particles)}});
  j["tracks"] = tracks;
  return j;
}

}  // namespace odotune::jobs

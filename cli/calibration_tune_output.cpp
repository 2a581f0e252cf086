#include "cli/calibration_tune_output.h"

#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "cli/output.h"

namespace odotune::cli {

namespace {

// Mean |R̂ − R|/R of both radii at the track's end [%]; nothing without truth.
std::optional<double> radius_error_pct(const TrackCalibrationScore& s) {
  if (!s.truth_final) return std::nullopt;
  const auto& e = s.final_params;
  const auto& t = *s.truth_final;
  return 50.0 * (std::abs(e.wheel_radius_left_m - t.wheel_radius_left_m) / t.wheel_radius_left_m +
                 std::abs(e.wheel_radius_right_m - t.wheel_radius_right_m) / t.wheel_radius_right_m);
}

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
int effective_particles(const filters::PfCalibratorParams& pf, CalibratorModel model) {
  CalibrationOptions o;
  o.method = calibration_method(model);
  o.pf = pf;
  return effective_pf_params(o).particles;
}

std::string convergence_text(const TrackCalibrationScore& s) {
  if (!s.truth_final) return "no truth";
  return s.convergence_time_s ? fmt::format("converged at {:.1f} s", *s.convergence_time_s) : "never converged";
}

}  // namespace

nlohmann::json calibration_tune_json(const CalibrationTuneOutcome& o, const CalibrationTuneContext& c) {
  const CalibrationTuneRequest& r = o.request;
  nlohmann::json j;
  j["model"] = to_string(TunedModel::calibration(r.model));
  j["solver"] = r.solver;
  j["seed"] = r.seed;
  if (r.solver == "pso") {
    j["particles"] = r.particles;
    j["iterations"] = r.iterations;
  }
  j["calibrator"] = {{"method", std::string(to_string(calibration_method(r.model)))},
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
  j["baseline_fitness"] = o.baseline_score;
  j["tuned_fitness"] = o.tuned_score;
  j["baseline"] = metrics_json(o.baseline_mean);
  j["tuned"] = metrics_json(o.tuned_mean);
  j["improvement_pct"] = improvement_json(o.baseline_mean, o.tuned_mean);
  j["evaluations"] = o.summary.evaluations;
  j["seconds"] = o.summary.seconds;
  j["termination"] = o.summary.termination;
  j["failures"] = o.failures;
  nlohmann::json tracks = nlohmann::json::array();
  for (std::size_t k = 0; k < o.baseline.tracks.size() && k < o.tuned.tracks.size(); ++k)
    tracks.push_back({{"track", o.baseline.tracks[k].track},
                      {"baseline", side_json(o.baseline.tracks[k], o.baseline.mean_particles)},
                      {"tuned", side_json(o.tuned.tracks[k], o.tuned.mean_particles)}});
  j["tracks"] = tracks;
  j["convergence"] = convergence_json(o.summary);
  return j;
}

void print_calibration_outcome(const CalibrationTuneOutcome& o) {
  const CalibrationTuneRequest& r = o.request;
  std::string names;
  for (const auto& t : o.baseline.tracks) names += (names.empty() ? "" : ", ") + t.track;
  fmt::print("tuned the {} calibrator's settings on {} with {} (seed {}); resampler {}, policy {}, "
             "calibrator seed {}\n",
             to_string(TunedModel::calibration(r.model)), names, r.solver, r.seed,
             filters::to_string(o.default_pf.resampler), filters::to_string(o.default_pf.policy),
             o.default_pf.seed);
  fmt::print("  score (lower is better): {:.4g} with the paper's defaults → {:.4g} tuned{}\n",
             o.baseline_score, o.tuned_score,
             o.default_kept ? " (the defaults scored best: kept)" : "");
  fmt::print("  calibrated odometry, dead-reckoning position error:\n");
  fmt::print("    RMSE {}\n", metric_change(o.baseline_mean.rmse_m, o.tuned_mean.rmse_m));
  fmt::print("    MAE  {}\n", metric_change(o.baseline_mean.mae_m, o.tuned_mean.mae_m));
  fmt::print("    MAXE {}\n", metric_change(o.baseline_mean.maxe_m, o.tuned_mean.maxe_m));
  for (std::size_t k = 0; k < o.baseline.tracks.size() && k < o.tuned.tracks.size(); ++k) {
    const auto& b = o.baseline.tracks[k];
    const auto& t = o.tuned.tracks[k];
    const auto eb = radius_error_pct(b.calibration), et = radius_error_pct(t.calibration);
    fmt::print("    {}: RMSE {}; {} → {}", b.track, metric_change(b.errors.rmse_m, t.errors.rmse_m),
               convergence_text(b.calibration), convergence_text(t.calibration));
    if (eb && et) fmt::print("; final radius error {:.3f} → {:.3f} %", *eb, *et);
    fmt::print("\n");
  }
  fmt::print("  mean particles per iteration: {:.0f} → {:.0f}\n", o.baseline.mean_particles,
             o.tuned.mean_particles);
  fmt::print("  settings:\n");
  for (std::size_t i = 0; i < o.params.size(); ++i)
    fmt::print("    {:<28} {:>12.6g}  (default {:.6g}) [{}]\n", o.param_names[i], o.params[i],
               o.default_params[i], o.param_units[i]);
  fmt::print("  {} evaluations in {:.2f} s ({}); failed evaluations: {}\n", o.summary.evaluations,
             o.summary.seconds, o.summary.termination, o.failures);
}

}  // namespace odotune::cli

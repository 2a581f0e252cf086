#include <odotune/jobs/calibration_tune_job.h>

#include <stdexcept>

#include <fmt/format.h>

#include <odotune/calibration/calibrated_odometry_errors.h>
#include <odotune/calibration/calibration_ranges.h>
#include <odotune/core/why.h>
#include <odotune/jobs/tune_job.h>
#include <odotune/tuner/nlopt_solver.h>
#include <odotune/tuner/problem.h>
#include <odotune/tuner/pso.h>

namespace odotune::jobs {

namespace {

bool same_robot(const filters::OdometryParams& a, const filters::OdometryParams& b) {
  return a.wheel_radius_left_m == b.wheel_radius_left_m && a.wheel_radius_right_m == b.wheel_radius_right_m &&
         a.wheel_base_m == b.wheel_base_m;
}

objectives::ErrorMetrics mean_errors(const CalibrationEvaluation& e) {
  std::vector<objectives::ErrorMetrics> all;
  for (const auto& t : e.tracks) all.push_back(t.errors);
  return mean_metrics(all);
}

}  // namespace

calibration::CalibrationMethod calibration_method(objectives::CalibratorModel model) {
  return model == objectives::CalibratorModel::pf ? calibration::CalibrationMethod::pf
                                                  : calibration::CalibrationMethod::adaptive_pf;
}

bool CalibrationTuneRequest::IsValid(std::string* why) const {
  if (!SolverSettings::IsValid(why)) return false;
  if (pf_particles && *pf_particles < 1) {
    return core::invalid(why, fmt::format("pf particles = {} must be ≥ 1 (or not given, for the paper's count)",
                                          *pf_particles));
  }
  return weights.IsValid(why);
}

filters::PfCalibratorParams default_calibrator(const CalibrationTuneRequest& r,
                                               const filters::OdometryParams& nominal) {
  filters::PfCalibratorParams p = r.model == objectives::CalibratorModel::adaptive_pf
                                      ? filters::PfCalibratorParams::adaptive_defaults()
                                      : filters::PfCalibratorParams{};
  const calibration::CalibrationRanges ranges = calibration::default_calibration_ranges(
      nominal);  // as `odotune calibrate`
  p.wheel_radius_left_m = ranges.wheel_radius_left_m;
  p.wheel_radius_right_m = ranges.wheel_radius_right_m;
  p.wheel_base_m = ranges.wheel_base_m;
  p.resampler = r.resampler;
  p.policy = r.policy;
  if (r.pf_particles) p.particles = *r.pf_particles;
  p.seed = r.pf_seed;
  p.adaptive = r.model == objectives::CalibratorModel::adaptive_pf;
  p.threads = 1;  // results do not depend on it; a grid runs cells side by side
  return p;
}

CalibrationEvaluation evaluate_calibrator(const std::vector<const calibration::CalibrationInput*>& inputs,
                                          objectives::CalibratorModel model,
                                          const filters::PfCalibratorParams& pf) {
  calibration::CalibrationOptions o;
  o.method = calibration_method(model);
  o.pf = pf;
  const calibration::CalibrationResult r = calibration::run_calibration(inputs, o);
  CalibrationEvaluation e;
  e.mean_particles = r.mean_particles;
  e.iterations = r.iterations;
  // Before the first estimate the filter's initial one is in force; on later
  // tracks the previous track's last (calibrated_odometry_errors.h).
  filters::OdometryParams before = filters::PfCalibrator(calibration::effective_pf_params(o)).estimate().params;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    CalibrationTrackScore s;
    s.track = inputs[k]->track_name;
    s.calibration = r.tracks.at(k);
    s.errors = calibration::calibrated_odometry_errors(*inputs[k], r.trace, static_cast<int>(k), before);
    before = s.calibration.final_params;
    e.tracks.push_back(std::move(s));
  }
  return e;
}

CalibrationTuneOutcome run_calibration_tune(const std::vector<const calibration::CalibrationInput*>& inputs,
                                            const CalibrationTuneRequest& request) {
  std::string why;
  if (!request.IsValid(&why)) throw std::invalid_argument(why);
  if (inputs.empty()) throw std::invalid_argument("no tracks to tune on");
  for (const auto* in : inputs)
    if (!same_robot(in->nominal, inputs.front()->nominal))
      throw std::invalid_argument(
          fmt::format("tracks '{}' and '{}' have different nominal wheel radii or base: a calibrator runs its "
                      "tracks one after another with one filter, so they must be recordings of one robot",
                      inputs.front()->track_name, in->track_name));

  CalibrationTuneOutcome out;
  out.request = request;
  out.default_pf = default_calibrator(request, inputs.front()->nominal);
  if (!out.default_pf.IsValid(&why)) throw std::invalid_argument("calibrator: " + why);
  const calibration::CalibrationObjective objective(
      inputs, out.default_pf, request.model == objectives::CalibratorModel::adaptive_pf, request.weights);
  const BoxProblem<calibration::CalibrationObjective> problem{&objective};
  out.default_params = calibration::calibration_params_of(out.default_pf);
  DefaultsTune t = run_solver_from_defaults(problem, request, objective.space(), out.default_params);
  out.param_names = std::move(t.param_names);
  out.param_units = std::move(t.param_units);
  out.summary = std::move(t.summary);
  out.baseline_score = t.baseline_fitness;
  out.default_kept = t.default_kept;
  out.tuned_score = t.tuned_fitness;
  out.params = std::move(t.params);
  // Kept defaults run exactly as the baseline (mm ↔ m may round the last bit).
  out.tuned_pf = out.default_kept ? out.default_pf
                                  : calibration::apply_calibration_params(out.default_pf, out.params);
  out.failures = objective.failures();

  out.baseline = evaluate_calibrator(inputs, request.model, out.default_pf);
  out.tuned = evaluate_calibrator(inputs, request.model, out.tuned_pf);
  out.baseline_mean = mean_errors(out.baseline);
  out.tuned_mean = mean_errors(out.tuned);
  return out;
}

}  // namespace odotune::jobs

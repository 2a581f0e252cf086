// The --json document of `tune --model pf-calib|adaptive-pf-calib`
// (odotune/cli/tune_output.h prints the result).
//
// --json keys (like the EKF tune JSON where it makes sense; lengths in metres):
//   model             "pf-calib" | "adaptive-pf-calib"
//   solver, seed      as the EKF tune JSON; particles, iterations for pso
//   calibrator        the fixed parts: {method ("pf" | "adaptive-pf"), resampler,
//                     policy, particles (N or initial N), seed, ext_from_gt_hz
//                     (0: the tracks' own v_ext/w_ext)}
//   params            tuned settings, name → value (calibration_space() names)
//   param_units       name → unit
//   default_params    the paper's defaults (the baseline), name → value
//   default_kept      true when the default scored better than the solver's best
//                     (then params = default_params)
//   score_weights     {radius, convergence, pose, cost} of the score
//   baseline_score, tuned_score   the objective's score (lower is better;
//                     calibration_objective.h); also as baseline_fitness and
//                     tuned_fitness, the EKF tune JSON's names
//   baseline, tuned   mean over tracks of the calibrated odometry's dead-reckoning
//                     position errors {rmse_m, mae_m, maxe_m, samples}
//   improvement_pct   {rmse, mae, maxe}: 100·(baseline − tuned)/baseline
//   evaluations, seconds, termination   the solver's
//   failures          evaluations that scored the penalty (calibrator failed)
//   tracks            per track: {track, baseline, tuned}, each {metrics…,
//                     final_params {wheel_radius_left_m, wheel_radius_right_m,
//                     wheel_base_m}, convergence_time_s (null: never/unknown),
//                     radius_error_pct (null without truth), mean_particles}
//   convergence       [{iteration, evaluations, best_fitness}] of the solver
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include <odotune/jobs/calibration_tune_job.h>

namespace odotune::jobs {

// The fixed parts the JSON records besides the request.
struct CalibrationTuneContext {
  double ext_from_gt_hz = 0.0;
};

nlohmann::json calibration_tune_json(const CalibrationTuneOutcome& o, const CalibrationTuneContext& c);
// Mean |R̂ − R|/R of both radii at the track's end [%]; nothing without truth.
std::optional<double> radius_error_pct(const calibration::TrackCalibrationScore& s);
// "converged at 12.3 s", "never converged" or "no truth".
std::string convergence_text(const calibration::TrackCalibrationScore& s);

}  // namespace odotune::jobs

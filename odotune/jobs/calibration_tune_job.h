// One tuning run of a particle-filter calibrator's settings: calibrator kind × tracks × solver × seed → the tuned settings (N_eff
// fraction, max-weight ratio, α, dispersion per particle, random-walk σ;
// odotune/calibration/calibration_objective.h), scored against the paper's default
// settings. The mirror of tune_job.h for calibrators; computation only (the
// commands parse and print), so `tune` and `grid` share it.
//
// Baseline: the calibrator with the paper's default settings
// (PfCalibratorParams{} for the plain PF, adaptive_defaults() for the
// adaptive one: N_th = 0.5·N, max-weight ratio 10, α = 1e-4, 0.01 mm of
// radius dispersion per particle, σ = 0.5 mm) and the request's fixed parts.
// Tuned: the solver's best point — or the default point when it scores
// better (the solver never evaluates the default itself with PSO), so the
// tuned score is never worse than the baseline's on the tuning tracks;
// `default_kept` says when that happened. NLopt starts from the default point.
//
// The calibrator runs the tracks one after another with one filter
// (calibration_run.h), so they must be recordings of one robot: equal nominal
// radii and wheel base. Its initial uniform ranges are `odotune calibrate`'s
// defaults: each radius nominal ± 5 %, the wheel base nominal ± 15 % (for the
// paper's wheelchair, R = 0.32 m and D = 0.65 m, its [0.305, 0.335] m and
// [0.55, 0.75] m to within 2.5 mm).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_objective.h>
#include <odotune/calibration/calibration_run.h>
#include <odotune/filters/pf_calibrator.h>
#include <odotune/jobs/tune_job.h>
#include <odotune/objectives/metrics.h>
#include <odotune/objectives/tuned_model.h>
#include <odotune/tuner/summary.h>

namespace odotune::jobs {

// The solver settings (SolverSettings, tune_job.h) and the calibrator's fixed parts.
struct CalibrationTuneRequest : SolverSettings {
  objectives::CalibratorModel model = objectives::CalibratorModel::adaptive_pf;
  // Fixed parts of the calibrator (not tuned).
  filters::Resampler resampler = filters::Resampler::systematic;
  filters::ResamplePolicy policy = filters::ResamplePolicy::neff;
  std::optional<int> pf_particles;  // N (plain) / initial N (adaptive); not given: the paper's 5000 / 8000
  std::uint64_t pf_seed = 1;        // the calibrator's own seed (same for every evaluation)
  calibration::CalibrationScoreWeights weights;

  bool IsValid(std::string* why) const;
};

// The paper's default calibrator of `model` for a robot with `nominal`
// parameters, with the request's fixed parts: the baseline's settings.
filters::PfCalibratorParams default_calibrator(const CalibrationTuneRequest& request,
                                               const filters::OdometryParams& nominal);
// The calibration method that runs `model`.
calibration::CalibrationMethod calibration_method(objectives::CalibratorModel model);

// A calibrator's run over tracks (one after another), scored per track.
struct CalibrationTrackScore {
  std::string track;
  objectives::ErrorMetrics errors;  // dead-reckoning position errors of the calibrated odometry [m]
  calibration::TrackCalibrationScore calibration;  // final estimate, convergence, RMSEs (calibration_run.h)
};
struct CalibrationEvaluation {
  std::vector<CalibrationTrackScore> tracks;
  double mean_particles = 0.0;
  long iterations = 0;
};
// Throws std::invalid_argument for invalid settings or inputs.
CalibrationEvaluation evaluate_calibrator(const std::vector<const calibration::CalibrationInput*>& inputs,
                                          objectives::CalibratorModel model,
                                          const filters::PfCalibratorParams& pf);

struct CalibrationTuneOutcome {
  CalibrationTuneRequest request;
  std::vector<std::string> param_names;  // calibration_space() order
  std::vector<std::string> param_units;
  std::vector<double> default_params;                  // physical, in param_units
  std::vector<double> params;                          // tuned, physical
  filters::PfCalibratorParams default_pf, tuned_pf;    // full settings (SI)
  double baseline_score = 0.0, tuned_score = 0.0;      // objective score, lower is better
  bool default_kept = false;                           // the default scored better than the solver's best
  CalibrationEvaluation baseline, tuned;               // per-track scores with either setting
  objectives::ErrorMetrics baseline_mean, tuned_mean;  // means over tracks
  long failures = 0;                                   // evaluations that scored the penalty
  tuner::Summary summary;                              // evaluations, seconds, termination, log
};

// Runs the solver; throws std::invalid_argument for an invalid request, no
// tracks or tracks of different robots, and std::runtime_error when the
// solver fails.
CalibrationTuneOutcome run_calibration_tune(const std::vector<const calibration::CalibrationInput*>& inputs,
                                            const CalibrationTuneRequest& request);

}  // namespace odotune::jobs

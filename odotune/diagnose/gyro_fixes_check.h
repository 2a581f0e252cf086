// The gyro judged against sparse absolute position fixes (no reference
// heading), a companion of sensor_checks.h, whose gyro regression needs a
// reference heading: dead reckoning with the gyro's heading and the wheels'
// distance against the fixes, gyro bias and scale (and a common distance
// scale) fitted on training windows and proven on held-out ones. Method,
// statistics and thresholds: docs/diagnosis-design.md, "Gyro against
// position fixes". No I/O; SI units; deterministic.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/fit.h>
#include <odotune/diagnose/sensor_checks.h>

namespace odotune::diagnose {

struct GyroFixesOptions {
  double window_s = 40.0;  // replay window [s] (make_windows; > 0); see header
  // A track shorter than 3 windows gets windows of a third of its span, but
  // not shorter than this [s] (a 71 s track: 3 windows of 23.7 s instead of
  // 2 of 40 s, too few for a held-out proof).
  double min_window_s = 20.0;
  RobustLoss loss = RobustLoss::huber;
  double loss_scale = 3.0;         // where the loss turns robust [fix sigmas]
  int max_iterations = 100;        // Levenberg-Marquardt iterations per fit
  double min_spread_sigmas = 2.0;  // windows whose dead reckoning moves less are not used
  bool fit_distance_scale = true;  // also fit q, a common scale of the wheel distance
  bool use_standstill = true;      // gyro means where both wheels stand still constrain b
  double min_standstill_s = 0.5;   // shortest standstill run used (after trimming) [s]
  double standstill_trim_s = 0.1;  // cut from both ends of a standstill run [s]
  double heldout_fraction = 0.3;   // share of the used windows held out (the last ones)
  double alpha = 1e-3;             // one-sided level of the held-out test
  double min_informative = 4.0;    // D_w a held-out window needs [normalised units]
  // As SensorCheckOptions (same meaning and defaults):
  double z_threshold = 4.0;          // significance: |value - noop| > z*std_error
  double relevance_window_s = 20.0;  // T of the relevance test [s]
  double relevance_factor = 2.0;     // drift must exceed this x noise drift ...
  double min_drift_rad = 1e-3;       // ... and this [rad]
  ModelOptions model;                // of the EffectModel giving the nominal distance

  bool IsValid(std::string* why) const;
};

// One held-out comparison (header comment): `alt` = the training fit,
// `ref` = the same with the tested parameters at their no-op values.
struct HeldoutComparison {
  std::string what;     // "joint", "gyro_scale.s", "gyro_bias.b"
  int windows = 0;      // held-out windows scored
  int informative = 0;  // of those, D_w >= min_informative
  int improved = 0;     // informative windows where SSE_alt < SSE_ref
  double ref_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();  // pooled, held-out
  double alt_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();
  double z = std::numeric_limits<double>::quiet_NaN();  // Stouffer's Z
  double p = 1.0;                                       // one-sided
  bool passed = false;                                  // informative >= 1 and p < alpha
};

struct GyroFixesCheck {
  // Verdicts: value/std_error/z/drift as the header comment. bins = used
  // windows; residual_sigma_radps is NaN (no rate regression here).
  GyroCheck gyro;
  int standstill_runs = 0;      // used standstill runs
  double standstill_s = 0.0;    // their total duration [s]
  double distance_scale = 1.0;  // fitted q (1 unless fit_distance_scale)
  double distance_scale_std_error = std::numeric_limits<double>::quiet_NaN();

  // The two standard errors behind Verdict::std_error = max(jackknife, model).
  double scale_jackknife_se = std::numeric_limits<double>::quiet_NaN();
  double scale_model_se = std::numeric_limits<double>::quiet_NaN();
  double bias_jackknife_se = std::numeric_limits<double>::quiet_NaN();
  double bias_model_se = std::numeric_limits<double>::quiet_NaN();

  // Window indices are make_windows(in, window_s)'s (a short last window
  // merged into the one before counts as that one).
  double window_s = 0.0;
  int num_windows = 0;                              // windows after the merge
  std::vector<int> used_windows;                    // fitted (all-window fit, jackknife)
  std::vector<int> skipped_windows;                 // outside the gyro, too few fixes, or no motion
  std::vector<int> train_windows, heldout_windows;  // split of used_windows
  double train_scale = std::numeric_limits<double>::quiet_NaN();  // training fit
  double train_bias_radps = std::numeric_limits<double>::quiet_NaN();
  HeldoutComparison joint, scale_own, bias_own;

  // In-sample position RMSE over the used windows (closed-form anchors):
  // nominal gyro dead reckoning (s = 1, b = 0, q = 1) and the all-window fit.
  double nominal_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();
  double fitted_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();
  bool converged = false;  // the all-window fit converged
  int fits = 0;            // Ceres solves (1 + training + jackknife)
  double time_s = 0.0;     // wall clock
};

// Throws std::invalid_argument (one line) for invalid options or an input
// whose arrays are inconsistent. An input the check cannot judge (no gyro,
// no wheel distance, fewer than 3 usable windows, ...) gives
// gyro.available = false and gyro.unavailable_reason.
GyroFixesCheck check_gyro_with_fixes(const DiagInput& in, const GyroFixesOptions& options = {});

}  // namespace odotune::diagnose

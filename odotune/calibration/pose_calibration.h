// Pose-domain batch calibration: R_L, R_R and D fitted so that the wheel
// odometry, dead-reckoned over segments of the runs, lands on the reference
// positions (ground truth, or absolute position fixes when a run has no
// ground truth). With whole runs as segments this is the classical offline
// fit of dead reckoning to motion capture (e.g. OptiOdom, Sousa et al., JINT
// 2022, which minimises the pose error of whole-run dead reckoning), and it
// minimises the very error a calibration is judged by: the dead-reckoning
// position error from the run's first pose.
//
// Segments. A warm start fits on short segments first (warm_start_segment_s)
// and the requested segments start from its result. Each run's reference stretch (its odometry rows with ground
// truth, or its fixes) is cut into abutting segments of
// PoseCalibrationOptions::segment_s (0: one segment per stretch, i.e. whole
// runs). A segment starts at an odometry row a and integrates the wheel
// rates of rows a+1.. with filters::diff_drive_step (l = ω_l R_L Δt,
// r = ω_r R_R Δt), as calibration_run.h's dead reckoning does.
//   ground truth: the start pose is the ground-truth pose at a (its heading
//     optionally fitted per segment: fit_start_heading); residuals at every
//     later row of the segment with ground truth;
//   fixes: the start pose (x, y, θ) at the odometry row at or before the
//     segment's first fix is fitted per segment (a nuisance parameter,
//     started from that fix and the best of 16 headings under the initial
//     parameters); residuals at every fix of the segment, the dead reckoning
//     taken to the fix's own time (a fraction of its odometry interval).
// Residual: the planar position error [m] (x and y), with a Huber loss of
// scale loss_scale_m against reference outliers. Ceres with automatic
// derivatives; the parameters are bounded below by 1 % of their initial
// values (positivity only).
//
// Standard errors: ceres::Covariance of the fit scaled by s² = 2·cost/(m − p)
// (m residuals, p parameters). Dead-reckoning errors are correlated along a
// segment, so these treat correlated residuals as independent and are
// optimistic (too small) for long segments; shorter segments make them more
// honest. NaN when a parameter is unobservable (e.g. D on runs that never
// turn).
#pragma once

#include <string>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/filters/odometry_params.h>

namespace odotune::calibration {

struct PoseCalibrationOptions {
  double segment_s = 0.0;          // segment length [s]; 0: whole runs (each reference stretch)
  bool fit_start_heading = false;  // ground truth: also fit each segment's start heading
  double loss_scale_m = 0.3;       // Huber scale of a position error [m]
  // Warm start: first fit on segments this long [s] (0: no warm start), then
  // on the requested ones from there. Long dead reckoning turns a wheel-base
  // error into whole turns of heading, and its cost has local minima far
  // from the truth (a robot 30 cm wide spinning for two minutes); short
  // segments have one basin that holds the truth. Skipped when segment_s is
  // already this short.
  double warm_start_segment_s = 10.0;
  int max_iterations = 200;  // Ceres iterations

  // True when every value is usable; otherwise *why names the first bad one.
  bool IsValid(std::string* why) const;
};

enum class PoseReference { ground_truth, fixes };

struct PoseCalibrationSummary {
  filters::OdometryParams params;
  double sd_radius_left_m = 0.0, sd_radius_right_m = 0.0, sd_wheel_base_m = 0.0;  // [m] (header)
  long segments = 0;                                                              // dead-reckoning segments
  long reference_points = 0;    // reference positions compared (2 residuals each)
  long ground_truth_runs = 0;   // runs whose reference is their ground truth
  long fix_runs = 0;            // runs whose reference is their position fixes
  double initial_rmse_m = 0.0;  // RMSE of the position errors at the initial parameters [m]
  double final_rmse_m = 0.0;    // ... at the fitted parameters (start poses refitted) [m]
  bool converged = false;       // Ceres reported CONVERGENCE
  std::string termination;      // Ceres' message
  // One line saying which residuals were used, e.g. "pose residuals: 11843
  // ground-truth positions over 3 whole-run segments (start heading from the
  // reference)".
  std::string residuals;
};

// Fits all inputs together from `initial` (one thread, deterministic). A run
// uses its ground truth when it has one (CalibrationInput::has_gt), else its
// fixes (at least 3). Throws std::invalid_argument for invalid options or
// initial parameters, a null input, or a run with neither reference (naming
// it).
PoseCalibrationSummary pose_calibrate(const std::vector<const CalibrationInput*>& inputs,
                                      const filters::OdometryParams& initial,
                                      const PoseCalibrationOptions& options = {});

}  // namespace odotune::calibration

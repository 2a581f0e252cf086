// Offline calibration of a body-velocity odometry: the twist a drive
// controller reports, or the velocity commands (odotune/tracks/odometry_input.h),
//   v(t) = scale_v · v_in(t − delay),   w(t) = scale_w · w_in(t − delay)
// with v_in, w_in the track's v_cmd, w_cmd under odotune/tracks/body_velocity.h's
// zero-order hold (odotune/filters/odometry_params.h, TwistCorrection). The delay is
// fitted for commands only: a command leads the motion by the drive's
// response, a measured twist does not (0).
//
// Fitted in the pose domain, as pose_calibration.h fits wheel geometry: dead
// reckoning over segments of the runs lands on the reference positions,
// ground truth (the segment starts at its pose), or the position fixes when
// a run has none (the start pose fitted per segment, from the first fix and
// the best of 16 headings). Dead reckoning steps at most step_s, every
// reference time being a step's end; a step's travel and turn are the scaled
// integrals of the delayed input (exact under the hold), advanced by the
// midpoint rule. Residual: the planar position error [m], Huber loss of
// scale loss_scale_m; scales bounded below by 1 %.
//
// The delay: a grid from 0 to max_delay_s in delay_step_s, each point
// fitting the scales on warm-start segments (warm_start_segment_s, where a
// lag shows as an error within seconds), then a grid of fine_delay_step_s
// around the best; the scales are then fitted at that delay on the requested
// segments (segment_s; 0: whole runs). Standard errors of the scales from
// ceres::Covariance scaled as pose_calibration.h (optimistic for long
// segments; NaN for a scale the runs do not determine, e.g. scale_w on runs
// that never turn).
#pragma once

#include <string>
#include <vector>

#include <odotune/filters/odometry_params.h>
#include <odotune/tracks/odometry_input.h>
#include <odotune/tracks/track.h>

namespace odotune::calibration {

struct TwistCalibrationOptions {
  // Segment length [s]; 0: whole runs. Short by default: over whole runs a
  // drifting heading lets the fit shrink the speed (MRCLAM robots 1-2:
  // scale_v 0.70 on 900 s runs, 0.93 on 10 s segments).
  double segment_s = 10.0;
  double warm_start_segment_s = 10.0;  // > 0 [s]: the delay search's segments and the warm start
  double step_s = 0.05;                // longest dead-reckoning step [s]
  double reference_step_s = 0.05;      // ground truth: at most one reference per this long [s]
  bool fit_delay = true;               // commands only
  double max_delay_s = 1.0;            // [s]
  double delay_step_s = 0.05;          // coarse grid [s]
  double fine_delay_step_s = 0.005;    // fine grid around the coarse best [s]
  double loss_scale_m = 0.3;           // Huber scale [m]
  int max_iterations = 100;            // Ceres iterations per fit
  bool IsValid(std::string* why) const;
};

struct TwistCalibrationSummary {
  tracks::OdometryInput input = tracks::OdometryInput::twist;
  filters::TwistCorrection params;
  double sd_scale_v = 0.0, sd_scale_w = 0.0;  // standard errors [-]
  long segments = 0, reference_points = 0;
  long ground_truth_runs = 0, fix_runs = 0;
  double initial_rmse_m = 0.0;  // position RMSE at the identity [m] (segments as fitted)
  double final_rmse_m = 0.0;    // ... at the fitted correction [m]
  bool converged = false;       // Ceres reported CONVERGENCE on the final fit
  std::string termination;      // Ceres' message
  std::string residuals;        // one line: what the fit used
};

// Dead reckoning of a track's body velocities corrected by `c`, from its
// first ground-truth pose within the v_cmd/w_cmd rows, compared at every
// later ground-truth row (steps of at most 0.05 s between them, exact under
// the hold): position and wrapped heading RMSE. NaN (0 samples) without
// ground truth there.
struct TwistScore {
  double pose_rmse_m = 0.0, heading_rmse_rad = 0.0;
  std::size_t samples = 0;
};
TwistScore score_twist(const tracks::Track& track, const filters::TwistCorrection& c);

// Fits all tracks together; each track's odometry must be `input` (twist or
// commands). Throws std::invalid_argument (one line naming the track) for
// invalid options, a wheel input, a track without body velocities or without
// a reference (ground truth or at least 3 fixes within its body velocities).
TwistCalibrationSummary calibrate_twist(const std::vector<const tracks::Track*>& tracks,
                                        tracks::OdometryInput input,
                                        const TwistCalibrationOptions& options = {});

}  // namespace odotune::calibration

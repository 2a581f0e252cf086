// Position errors (RMSE, MAE, MAXE) of a calibrated odometry's dead reckoning
// against ground truth: the metrics `tune` and `grid` report for a calibrator
// (calibration_run.h scores RMSE only). The dead reckoning is calibration_
// run.h's: from the track's first odometry row with ground truth (x, y, θ), at
// its pose, each later row r integrates its wheel rates over (t[r−1], t[r]]
// with filters::diff_drive_step (l = ω_l R_L Δt, r = ω_r R_R Δt) using the
// parameters current at t[r]: those of the last estimate at or before t[r],
// or `before` until the track's first estimate. The error at a row with
// ground truth is the planar distance to it [m]; the start row is not
// counted. No ground truth: zero samples. The RMSE equals calibration_run's
// TrackCalibrationScore::pose_rmse_m for the same parameters (up to rounding).
#pragma once

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_run.h>
#include <odotune/objectives/metrics.h>

namespace odotune::calibration {

// Dead reckoning with the estimates of `trace` that belong to track
// `track_index` (trace.track[k] == track_index; times on the track's clock).
// `before`: the parameters in force before that track's first estimate — an
// online filter's estimate at the track's start (on the first track its
// initial estimate, e.g. filters::PfCalibrator(p).estimate().params; on a
// later track the previous track's last estimate).
objectives::ErrorMetrics calibrated_odometry_errors(const CalibrationInput& input,
                                                    const CalibrationTrace& trace, int track_index,
                                                    const filters::OdometryParams& before);

// Dead reckoning with fixed parameters (e.g. the nominal ones).
objectives::ErrorMetrics fixed_odometry_errors(const CalibrationInput& input,
                                               const filters::OdometryParams& params);

}  // namespace odotune::calibration

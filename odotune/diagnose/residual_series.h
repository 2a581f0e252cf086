// The residual series of a window replay (locate.h's input): one row per
// reference sample scored by a replayed window, with the error predicted −
// reference and the robot's state there.
//
// State per row. Position from the reference sample. Speed, yaw rate and
// acceleration from the NOMINAL odometry (DiagInput), not from the
// reference: a model error of a few per cent does not matter for "which
// conditions does the residual grow with", while differentiating 1 Hz fixes
// with 50 mm noise would. Cumulative nominal travel s(t) and heading h(t) at
// the odometry nodes (wheel angles × nominal radii, or body velocities
// integrated by the trapezoid rule), linearly interpolated; then
//   v(t) = (s(t+δ) − s(t−δ)) / 2δ,  w(t) = (h(t+δ) − h(t−δ)) / 2δ,  δ = rate_half_s,
//   a(t) = (v(t+δa) − v(t−δa)) / 2δa,  δa = accel_half_s,
// with the interval clipped to the odometry's span. Travel is signed, so v < 0
// when reversing.
#pragma once

#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/locate.h>
#include <odotune/diagnose/window_replay.h>

namespace odotune::diagnose {

struct ResidualSeriesOptions {
  double rate_half_s = 0.25;  // δ of v and w [s]
  double accel_half_s = 0.5;  // δa of the acceleration [s]
};

// Nominal body speed [m/s], yaw rate [rad/s] and acceleration [m/s²] at times
// t_s (see the file comment).
struct NominalKinematics {
  std::vector<double> v_mps, w_radps, accel_mps2;
};
NominalKinematics nominal_kinematics(const DiagInput& in, const std::vector<double>& t_s,
                                     const ResidualSeriesOptions& options = {});

// Rows in the order of `windows` (make_windows of the replay), samples whose
// prediction is NaN (window not replayed) left out. `replayed` must hold one
// predicted pose per reference sample (ReplayResult::pred_*). The heading
// error is filled when the reference has heading (wrapped to (−π, π]).
ResidualSeries residual_series(const DiagInput& in, const std::vector<Window>& windows,
                               const ReplayResult& replayed, const ResidualSeriesOptions& options = {});

}  // namespace odotune::diagnose

// Track samples shared by the input builders of objectives/ (calibration_
// input.h, fusion_input.h): the ground-truth pose series of a track and a
// per-row variance with a fallback.
#pragma once

#include <cstddef>
#include <vector>

#include <odotune/objectives/pose_series.h>
#include <odotune/tracks/track.h>

namespace odotune::objectives {

// Longest ground-truth gap interpolated across when a pose is needed between
// ground-truth rows [s]: long enough for any motion-capture jitter or a
// missed frame, short enough not to invent a pose across a real dropout.
inline constexpr double kMaxGtGapS = 0.5;

// The track's ground-truth rows with x, y AND theta, theta unwrapped (each
// step taken as the wrapped difference, so an already unwrapped series is
// unchanged). Empty when the track has no gt_x/gt_y/gt_theta.
PoseSeries ground_truth_series(const tracks::Track& track);

// col[row] when the column exists and the value is finite and > 0, else
// `fallback` (a sensor variance column with empty or unusable cells).
double positive_or(const std::vector<double>& col, std::size_t row, double fallback);

}  // namespace odotune::objectives

// The dead reckoning of a calibration input (calibration_input.h) that every
// calibration score shares (calibration_run.h's TrackCalibrationScore and
// dead_reckoned_path, calibrated_odometry_errors.h): from the first odometry
// row with ground truth, at its pose, each later row r integrates its wheel
// rates over (t[r−1], t[r]] with odotune/core/planar_motion.h's midpoint_advance (l = ω_l R_L Δt,
// r = ω_r R_R Δt), using the parameters params_at(t[r]).
#pragma once

#include <cstddef>

#include <odotune/calibration/calibration_input.h>
#include <odotune/core/planar_motion.h>
#include <odotune/filters/diff_drive.h>
#include <odotune/filters/odometry_params.h>

namespace odotune::calibration {

// Calls visit(row, pose) for the start row (its ground-truth pose) and then
// for every later odometry row with the dead-reckoned pose there (whether or
// not the row has ground truth: in.has_gt_row(row) says). Visits nothing
// when no row has ground truth. params_at(t_s) returns the
// filters::OdometryParams in force at t_s.
template <typename ParamsAt, typename Visit>
void dead_reckon(const CalibrationInput& in, ParamsAt&& params_at, Visit&& visit) {
  const std::size_t n = in.t.size();
  std::size_t start = 0;
  while (start < n && !in.has_gt_row(start)) ++start;
  if (start >= n) return;
  filters::Pose pose;
  pose << in.gt_x[start], in.gt_y[start], in.gt_theta[start];
  visit(start, static_cast<const filters::Pose&>(pose));
  for (std::size_t r = start + 1; r < n; ++r) {
    const filters::OdometryParams& p = params_at(in.t[r]);
    const double dt = in.t[r] - in.t[r - 1];
    const double l = in.omega_l[r] * p.wheel_radius_left_m * dt;
    const double rr = in.omega_r[r] * p.wheel_radius_right_m * dt;
    core::midpoint_advance(&pose(filters::kX), &pose(filters::kY), &pose(filters::kTheta), l, rr,
                           p.wheel_base_m);
    visit(r, static_cast<const filters::Pose&>(pose));
  }
}

}  // namespace odotune::calibration

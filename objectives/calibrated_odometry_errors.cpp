#include "objectives/calibrated_odometry_errors.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "filters/diff_drive.h"

namespace odotune {

namespace {

// Dead reckoning over the rows with the parameters `params_at(t)` at time t.
template <typename ParamsAt>
ErrorMetrics dead_reckoning_errors(const CalibrationInput& in, ParamsAt&& params_at) {
  ErrorAccumulator acc;
  if (!in.has_gt) return acc.metrics();
  const std::size_t n = in.t.size();
  auto has_gt_row = [&](std::size_t r) {
    return !std::isnan(in.gt_x[r]) && !std::isnan(in.gt_y[r]) && !std::isnan(in.gt_theta[r]);
  };
  std::size_t start = 0;
  while (start < n && !has_gt_row(start)) ++start;
  if (start == n) return acc.metrics();
  filters::Pose pose;
  pose << in.gt_x[start], in.gt_y[start], in.gt_theta[start];
  for (std::size_t r = start + 1; r < n; ++r) {
    const filters::OdometryParams& p = params_at(in.t[r]);
    const double dt = in.t[r] - in.t[r - 1];
    const filters::WheelTravel u{in.omega_l[r] * p.wheel_radius_left_m * dt,
                                 in.omega_r[r] * p.wheel_radius_right_m * dt};
    pose = filters::diff_drive_step(pose, u, p.wheel_base_m).next;
    if (has_gt_row(r)) acc.add(std::hypot(pose(filters::kX) - in.gt_x[r], pose(filters::kY) - in.gt_y[r]));
  }
  return acc.metrics();
}

}  // namespace

ErrorMetrics calibrated_odometry_errors(const CalibrationInput& in, const CalibrationTrace& trace,
                                        int track_index, const filters::OdometryParams& before) {
  // This track's estimates, in time order (the trace is in iteration order).
  const std::size_t n = std::min({trace.track.size(), trace.t.size(), trace.estimate.size()});
  std::vector<std::size_t> rows;
  for (std::size_t k = 0; k < n; ++k)
    if (trace.track[k] == track_index) rows.push_back(k);
  // Rows arrive in increasing time: advance through the estimates once.
  std::size_t next = 0;  // first of `rows` not yet in force
  const filters::OdometryParams* current = &before;
  return dead_reckoning_errors(in, [&](double t_s) -> const filters::OdometryParams& {
    while (next < rows.size() && trace.t[rows[next]] <= t_s) current = &trace.estimate[rows[next++]].params;
    return *current;
  });
}

ErrorMetrics fixed_odometry_errors(const CalibrationInput& in, const filters::OdometryParams& params) {
  return dead_reckoning_errors(in, [&](double) -> const filters::OdometryParams& { return params; });
}

}  // namespace odotune

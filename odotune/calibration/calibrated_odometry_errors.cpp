#include <odotune/calibration/calibrated_odometry_errors.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <odotune/calibration/dead_reckoning.h>
#include <odotune/filters/diff_drive.h>

namespace odotune::calibration {

namespace {

// Dead-reckoning errors (dead_reckoning.h) with the parameters `params_at(t)`.
template <typename ParamsAt>
objectives::ErrorMetrics dead_reckoning_errors(const CalibrationInput& in, ParamsAt&& params_at) {
  objectives::ErrorAccumulator acc;
  if (!in.has_gt) return acc.metrics();
  bool start = true;  // the first visit is the start row, not scored
  dead_reckon(in, params_at, [&](std::size_t r, const filters::Pose& pose) {
    if (!start && in.has_gt_row(r))
      acc.add(std::hypot(pose(filters::kX) - in.gt_x[r], pose(filters::kY) - in.gt_y[r]));
    start = false;
  });
  return acc.metrics();
}

}  // namespace

objectives::ErrorMetrics calibrated_odometry_errors(const CalibrationInput& in, const CalibrationTrace& trace,
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

objectives::ErrorMetrics fixed_odometry_errors(const CalibrationInput& in,
                                               const filters::OdometryParams& params) {
  return dead_reckoning_errors(in, [&](double) -> const filters::OdometryParams& { return params; });
}

}  // namespace odotune::calibration

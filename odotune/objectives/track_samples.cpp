#include <odotune/objectives/track_samples.h>

#include <cmath>

namespace odotune::objectives {

PoseSeries ground_truth_series(const tracks::Track& track) {
  PoseSeries s;
  if (!track.has_gt() || !track.has(tracks::Col::gt_theta)) return s;
  const auto& gx = track.col(tracks::Col::gt_x);
  const auto& gy = track.col(tracks::Col::gt_y);
  const auto& gth = track.col(tracks::Col::gt_theta);
  double last_raw = 0.0, last_unwrapped = 0.0;
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (std::isnan(gx[i]) || std::isnan(gy[i]) || std::isnan(gth[i])) continue;
    const double th = s.size() == 0 ? gth[i] : last_unwrapped + core::wrap_angle(gth[i] - last_raw);
    last_raw = gth[i];
    last_unwrapped = th;
    s.push_back(track.t()[i], PlanarPose{gx[i], gy[i], th});
  }
  return s;
}

double positive_or(const std::vector<double>& col, std::size_t row, double fallback) {
  if (col.empty()) return fallback;
  const double v = col[row];
  return std::isfinite(v) && v > 0.0 ? v : fallback;
}

}  // namespace odotune::objectives

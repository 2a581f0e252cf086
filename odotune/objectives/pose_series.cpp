#include <odotune/objectives/pose_series.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace odotune::objectives {

std::optional<PlanarPose> interpolate_pose(const PoseSeries& s, double t_s, double max_gap_s) {
  const std::size_t n = s.size();
  if (n == 0 || !(t_s >= s.t.front()) || !(t_s <= s.t.back())) return std::nullopt;
  // First sample strictly after t_s; the one before it is at or before t_s.
  const auto it = std::upper_bound(s.t.begin(), s.t.end(), t_s);
  const auto hi = static_cast<std::size_t>(it - s.t.begin());
  const std::size_t lo = hi - 1;  // hi ≥ 1 since t_s ≥ t.front()
  if (s.t[lo] == t_s) return PlanarPose{s.x[lo], s.y[lo], s.theta[lo]};
  if (hi >= n) return std::nullopt;  // unreachable: t_s ≤ t.back() and t_s ≠ t[lo]
  const double gap = s.t[hi] - s.t[lo];
  if (gap > max_gap_s) return std::nullopt;
  const double f = (t_s - s.t[lo]) / gap;
  auto lerp = [f](double a, double b) { return a + f * (b - a); };
  return PlanarPose{lerp(s.x[lo], s.x[hi]), lerp(s.y[lo], s.y[hi]), lerp(s.theta[lo], s.theta[hi])};
}

std::optional<filters::BodyVelocity> central_difference_velocity(const PoseSeries& s, double t_s,
                                                                 double half_window_s, double max_gap_s) {
  const auto a = interpolate_pose(s, t_s - half_window_s, max_gap_s);
  const auto b = interpolate_pose(s, t_s + half_window_s, max_gap_s);
  if (!a || !b) return std::nullopt;
  const double period = 2.0 * half_window_s;
  const double dtheta = b->theta_rad - a->theta_rad;
  const double half = 0.5 * dtheta;
  if (std::abs(half) >= 0.5 * std::numbers::pi) return std::nullopt;
  const double theta_m = 0.5 * (a->theta_rad + b->theta_rad);
  const double along = (b->x_m - a->x_m) * std::cos(theta_m) + (b->y_m - a->y_m) * std::sin(theta_m);
  const double sinc = half == 0.0 ? 1.0 : std::sin(half) / half;
  return filters::BodyVelocity{along / period / sinc, dtheta / period};
}

}  // namespace odotune::objectives

#include <odotune/rlnode/gps_alignment.h>

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace odotune::rlnode {

GpsAlignment fit_gps_alignment(const Recording& rec, const ReplaySettings& settings, double seconds) {
  if (rec.gps_sensor < 0 || rec.fixes.empty()) {
    throw std::invalid_argument(
        fmt::format("{}: the GPS heading fit needs navsat_transform_node's output as an input "
                    "and NavSatFix messages in the bag",
                    rec.bag.string()));
  }
  const std::int64_t until = rec.start_ns + static_cast<std::int64_t>(seconds * 1e9);
  std::vector<FixRole> roles(rec.fixes.size(), FixRole::absent);
  for (std::size_t i = 0; i < rec.fixes.size(); ++i) {
    if (rec.fixes[i].stamp_ns < until) roles[i] = FixRole::score;
  }
  // The dead reckoning runs ekf_node's filter whichever the file runs: the
  // UKF's heading mean turns by π once the unmeasured heading's variance passes
  // 2 rad² (odotune/filters/rl_ukf.h), within the seconds a fit needs.
  ReplaySettings dead_reckoning = settings;
  dead_reckoning.filter = filters::rl::RlFilterType::ekf;
  // The fit compares raw fixes with the dead reckoning: navsat need not wait
  // for a datum (or an IMU heading) to pass them on.
  Recording fit = rec;
  fit.gps_transform.fixed = true;
  const ReplayOutput out = replay(fit, make_schedule(fit, roles, until), dead_reckoning);
  GpsAlignment a;
  a.fixes = static_cast<int>(out.scored.size());
  Eigen::Vector2d mp = Eigen::Vector2d::Zero(), mq = Eigen::Vector2d::Zero();
  for (const ScoredFix& s : out.scored) {
    mp += rec.fixes[s.fix].p.head<2>();
    mq += s.predicted.head<2>();
  }
  if (a.fixes < 5) {
    throw std::invalid_argument(
        fmt::format("{}: {} fixes in the first {} s; the GPS heading fit needs at least 5", rec.bag.string(),
                    a.fixes, seconds));
  }
  mp /= a.fixes;
  mq /= a.fixes;
  double dot = 0.0, cross = 0.0;
  for (const ScoredFix& s : out.scored) {
    const Eigen::Vector2d p = rec.fixes[s.fix].p.head<2>() - mp, q = s.predicted.head<2>() - mq;
    dot += p.dot(q);
    cross += p.x() * q.y() - p.y() * q.x();
    a.span_m = std::max(a.span_m, p.norm());
  }
  if (a.span_m < 5.0) {
    throw std::invalid_argument(
        fmt::format("{}: the fixes of the first {} s lie within {:.1f} m of their mean; the GPS "
                    "heading fit needs at least 5 m of driving (give more seconds)",
                    rec.bag.string(), seconds, a.span_m));
  }
  const double phi = std::atan2(cross, dot);
  a.transform.fixed = true;
  a.transform.rotation_rad = phi;
  a.transform.grid_origin = {mp.x(), mp.y(), rec.params.navsat.zero_altitude ? 0.0 : rec.fixes.front().p.z()};
  a.transform.odom_origin = {mq.x(), mq.y(), 0.0};
  double sum = 0.0;
  for (const ScoredFix& s : out.scored) {
    sum += (fix_in_odom(rec.fixes[s.fix], a.transform) - s.predicted).head<2>().squaredNorm();
  }
  a.rms_m = std::sqrt(sum / a.fixes);
  // navsat's rotation is yaw_odom − (imu_yaw + declination + yaw_offset + convergence)
  // at the datum (the first fix; here the filter's yaw there without GPS).
  // The IMU's heading is its last before the first fix.
  if (const auto* heading = navsat_heading_at(rec, rec.fixes.front().receive_ns)) {
    const ScoredFix& first = out.scored.front();
    a.yaw_offset_rad = filters::rl::normalize_angle(first.predicted_yaw - phi -
                                                    (heading->second - rec.params.navsat.yaw_offset) -
                                                    rec.fixes[first.fix].convergence_rad);
  }
  return a;
}

}  // namespace odotune::rlnode

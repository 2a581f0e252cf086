#include <odotune/learned/odometry_metrics.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <odotune/filters/velocity_ukf.h>
#include <odotune/objectives/pose_series.h>

namespace odotune::learned {
namespace {

constexpr double kMetricNaN = std::numeric_limits<double>::quiet_NaN();

bool usable(double a, double b) { return std::isfinite(a) && std::isfinite(b); }

}  // namespace

SeriesErrors series_errors(const std::vector<double>& est, const std::vector<double>& truth,
                           const std::vector<double>& var, std::size_t first) {
  SeriesErrors r;
  double sum_abs = 0, sum_sq = 0, sum_t = 0, sum_t2 = 0, sum_nees = 0;
  std::size_t n_nees = 0;
  const bool with_var = !var.empty();
  for (std::size_t k = first; k < est.size() && k < truth.size(); ++k) {
    if (!usable(est[k], truth[k])) continue;
    const double e = est[k] - truth[k];
    sum_abs += std::abs(e);
    sum_sq += e * e;
    sum_t += truth[k];
    sum_t2 += truth[k] * truth[k];
    ++r.samples;
    if (with_var && std::isfinite(var[k]) && var[k] > 0) {
      sum_nees += e * e / var[k];
      ++n_nees;
    }
  }
  if (r.samples == 0) return {kMetricNaN, kMetricNaN, kMetricNaN, kMetricNaN, 0};
  const auto n = static_cast<double>(r.samples);
  r.mae = sum_abs / n;
  r.rmse = std::sqrt(sum_sq / n);
  const double ss_tot = sum_t2 - sum_t * sum_t / n;  // Σ (y − ȳ)²
  r.r2 = ss_tot > 0 ? 1.0 - sum_sq / ss_tot : kMetricNaN;
  r.nees = n_nees > 0 ? sum_nees / static_cast<double>(n_nees) : kMetricNaN;
  return r;
}

PoseTrack dead_reckon(const FusionInput& in, const std::vector<double>& v, const std::vector<double>& w) {
  PoseTrack p;
  const std::size_t n = in.size();
  p.x.assign(n, kMetricNaN);
  p.y.assign(n, kMetricNaN);
  p.theta.assign(n, kMetricNaN);
  if (n == 0) return p;
  filters::PlanarPose pose;
  if (in.has_gt && std::isfinite(in.gt_x[0]) && std::isfinite(in.gt_theta[0]))
    pose = {in.gt_x[0], in.gt_y[0], in.gt_theta[0]};
  p.x[0] = pose.x_m;
  p.y[0] = pose.y_m;
  p.theta[0] = pose.theta_rad;
  for (std::size_t k = 1; k < n; ++k) {
    pose = filters::integrate_pose(pose, v[k], w[k], in.dt_s);
    p.x[k] = pose.x_m;
    p.y[k] = pose.y_m;
    p.theta[k] = pose.theta_rad;
  }
  return p;
}

double PoseErrorSum::rmse() const { return n > 0 ? std::sqrt(sum_sq / static_cast<double>(n)) : kMetricNaN; }

PoseErrorSum dead_reckoning_errors(const FusionInput& in, const std::vector<double>& v,
                                   const std::vector<double>& w, double window_s, std::size_t first,
                                   std::size_t end) {
  PoseErrorSum out;
  end = std::min(end, in.size());
  const auto has_pose = [&in](std::size_t k) {
    return std::isfinite(in.gt_x[k]) && std::isfinite(in.gt_y[k]) && std::isfinite(in.gt_theta[k]);
  };
  const auto steps = window_s > 0.0 ? static_cast<std::size_t>(std::llround(window_s / in.dt_s))
                                    : std::numeric_limits<std::size_t>::max();
  std::size_t k = first;
  while (k < end) {
    while (k < end && !has_pose(k)) ++k;  // the stretch starts at a ground-truth pose
    if (k >= end) break;
    const std::size_t stop = std::min(end, steps > end - k ? end : k + steps);
    filters::PlanarPose pose{in.gt_x[k], in.gt_y[k], in.gt_theta[k]};
    for (std::size_t j = k + 1; j < stop; ++j) {
      pose = filters::integrate_pose(pose, v[j], w[j], in.dt_s);
      if (!usable(in.gt_x[j], in.gt_y[j])) continue;
      const double ex = pose.x_m - in.gt_x[j], ey = pose.y_m - in.gt_y[j];
      if (!std::isfinite(ex) || !std::isfinite(ey)) continue;
      out.sum_sq += ex * ex + ey * ey;
      ++out.n;
    }
    k = stop;
  }
  return out;
}

OdometryErrors odometry_errors(const FusionInput& in, const std::vector<double>& v,
                               const std::vector<double>& w, const std::vector<double>& var_v,
                               const std::vector<double>& var_w, const std::vector<double>& cov_vw,
                               const PoseTrack* pose) {
  OdometryErrors r;
  r.v = series_errors(v, in.v_true, var_v);
  r.w = series_errors(w, in.w_true, var_w);

  PoseTrack own;
  r.xy_rmse_10s = r.xy_rmse_60s = kMetricNaN;
  if (pose == nullptr) {
    own = dead_reckon(in, v, w);
    pose = &own;
    r.xy_rmse_10s = dead_reckoning_errors(in, v, w, 10.0).rmse();
    r.xy_rmse_60s = dead_reckoning_errors(in, v, w, 60.0).rmse();
  }
  // Position: error norm; R² over X and Y stacked (paper eq. 9 on both axes).
  double sum_abs = 0, sum_sq = 0, sx = 0, sy = 0, sxx = 0, syy = 0;
  double th_abs = 0, th_sq = 0;
  std::size_t n = 0;
  for (std::size_t k = 1; k < in.size(); ++k) {
    if (!usable(in.gt_x[k], in.gt_y[k]) || !usable(pose->x[k], pose->y[k])) continue;
    const double ex = pose->x[k] - in.gt_x[k], ey = pose->y[k] - in.gt_y[k];
    const double e2 = ex * ex + ey * ey;
    sum_abs += std::sqrt(e2);
    sum_sq += e2;
    sx += in.gt_x[k];
    sy += in.gt_y[k];
    sxx += in.gt_x[k] * in.gt_x[k];
    syy += in.gt_y[k] * in.gt_y[k];
    const double eth = core::wrap_angle(pose->theta[k] - in.gt_theta[k]);
    th_abs += std::abs(eth);
    th_sq += eth * eth;
    ++n;
  }
  if (n > 0) {
    const auto nd = static_cast<double>(n);
    const double ss_tot = (sxx - sx * sx / nd) + (syy - sy * sy / nd);
    r.xy = {sum_abs / nd, std::sqrt(sum_sq / nd), ss_tot > 0 ? 1.0 - sum_sq / ss_tot : kMetricNaN, kMetricNaN,
            n};
    r.theta = {th_abs / nd, std::sqrt(th_sq / nd), kMetricNaN, kMetricNaN, n};
  } else {
    r.xy = r.theta = {kMetricNaN, kMetricNaN, kMetricNaN, kMetricNaN, 0};
  }

  // Joint NEES of (V, W) with the full covariance (paper eq. 10).
  r.nees_vw = kMetricNaN;
  if (!var_v.empty() && !var_w.empty()) {
    double sum = 0;
    std::size_t m = 0;
    for (std::size_t k = 1; k < in.size(); ++k) {
      if (!usable(v[k], in.v_true[k]) || !usable(w[k], in.w_true[k])) continue;
      filters::VelocityCov P;
      const double c = cov_vw.empty() ? 0.0 : cov_vw[k];
      P << var_v[k], c, c, var_w[k];
      const double e = filters::nees({in.v_true[k], in.w_true[k]}, {v[k], w[k]}, P);
      if (!std::isfinite(e)) continue;
      sum += e;
      ++m;
    }
    if (m > 0) r.nees_vw = sum / static_cast<double>(m);
  }
  return r;
}

}  // namespace odotune::learned

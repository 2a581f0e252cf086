// A small self-contained track for objective tests: a robot with a slightly
// mis-measured right wheel drives a wavy loop; ticks at `rate_hz`, gyro,
// fixes at 1 Hz with σ = 60 mm and exact ground truth. Independent of the
// simulator so these tests pin the objective layer alone.
#pragma once

#include <cmath>
#include <random>

#include <odotune/tracks/track.h>

namespace odotune::testing_support {

inline tracks::Track synthetic_track(std::uint64_t seed, double duration_s = 60.0, double rate_hz = 50.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> N(0.0, 1.0);
  const double R = 0.05, D = 0.30, tpr = 4096.0, true_R_right = 0.05 * 1.01;
  tracks::TrackData d;
  d.meta.name = "synthetic";
  d.meta.ticks_per_rev = tpr;
  d.meta.wheel_radius_left_m = R;
  d.meta.wheel_radius_right_m = R;
  d.meta.wheel_base_m = D;
  const int n = static_cast<int>(duration_s * rate_hz);
  const double dt = 1.0 / rate_hz;
  for (tracks::Col c : {tracks::Col::gyro_z, tracks::Col::aps_x, tracks::Col::aps_y, tracks::Col::gt_x,
                        tracks::Col::gt_y, tracks::Col::gt_theta})
    d.col(c).reserve(static_cast<std::size_t>(n));
  double x = 0, y = 0, th = 0, ang_l = 0, ang_r = 0;
  for (int i = 0; i < n; ++i) {
    const double t = i * dt;
    const double v = 0.4, w = 0.6 * std::sin(0.3 * t);
    // Wheel rates commanded from the nominal model; the true right wheel is bigger.
    const double om_l = (v - 0.5 * w * D) / R, om_r = (v + 0.5 * w * D) / R;
    if (i > 0) {
      ang_l += om_l * dt;
      ang_r += om_r * dt;
      const double vt = 0.5 * (om_l * R + om_r * true_R_right);
      const double wt = (om_r * true_R_right - om_l * R) / D;
      x += vt * std::cos(th + 0.5 * wt * dt) * dt;
      y += vt * std::sin(th + 0.5 * wt * dt) * dt;
      th += wt * dt;
    }
    d.t.push_back(t);
    d.ticks_l.push_back(static_cast<std::int64_t>(std::floor(ang_l / (2 * M_PI) * tpr)));
    d.ticks_r.push_back(static_cast<std::int64_t>(std::floor(ang_r / (2 * M_PI) * tpr)));
    d.col(tracks::Col::gyro_z).push_back((om_r * true_R_right - om_l * R) / D + 0.002 * N(rng));
    const bool fix = i % static_cast<int>(rate_hz) == 0 && i > 0;
    d.col(tracks::Col::aps_x).push_back(fix ? x + 0.06 * N(rng) : std::nan(""));
    d.col(tracks::Col::aps_y).push_back(fix ? y + 0.06 * N(rng) : std::nan(""));
    d.col(tracks::Col::gt_x).push_back(x);
    d.col(tracks::Col::gt_y).push_back(y);
    d.col(tracks::Col::gt_theta).push_back(th);
  }
  return tracks::Track(std::move(d));
}

}  // namespace odotune::testing_support

// The error metrics of Fariña et al., Sensors 2023, 23, 961, eqs. 9–10, for a
// velocity series and the pose dead-reckoned from it (Tables 1–3):
// MAE, RMSE and R² of V and W; MAE, RMSE and R² of the position (X, Y
// stacked: R² = 1 − Σ‖p̂ − p‖² / Σ‖p − p̄‖²) and MAE, RMSE of θ; NEES where
// a variance is given. Only steps with ground truth count.
#pragma once

#include <cstddef>
#include <vector>

#include <odotune/learned/fusion_input.h>

namespace odotune::learned {

struct SeriesErrors {
  double mae = 0.0, rmse = 0.0, r2 = 0.0;
  double nees = 0.0;  // mean e²/var (one dimension; NaN when no variance given)
  std::size_t samples = 0;
};

struct OdometryErrors {
  SeriesErrors v, w;  // [m/s], [rad/s]
  SeriesErrors xy;    // position error norm [m]; r2 over X and Y stacked
  // Position RMSE of dead reckoning restarted at the ground truth every 10 s
  // and every 60 s (dead_reckoning_errors) [m]; NaN when the pose is given
  // (a filter's, which is not restarted) or without ground truth.
  double xy_rmse_10s = 0.0, xy_rmse_60s = 0.0;
  SeriesErrors theta;    // wrapped heading error [rad]; r2 not used (NaN)
  double nees_vw = 0.0;  // mean (e ᵀ P⁻¹ e) of (V, W) with the full covariance when given, else NaN
};

// Errors of a scalar series against truth (NaN truth steps skipped). var may
// be empty (then nees is NaN) or as long as est.
SeriesErrors series_errors(const std::vector<double>& est, const std::vector<double>& truth,
                           const std::vector<double>& var, std::size_t first = 1);

// Dead reckoning of (v, w) per step from the ground-truth pose at step 0 by
// paper eq. 3 (filters::integrate_pose).
struct PoseTrack {
  std::vector<double> x, y, theta;
};
PoseTrack dead_reckon(const FusionInput& in, const std::vector<double>& v, const std::vector<double>& w);

// Squared position errors of dead reckoning, pooled (RMSE = √(sum_sq / n)).
struct PoseErrorSum {
  double sum_sq = 0.0;  // [m²]
  std::size_t n = 0;
  double rmse() const;  // [m]; NaN when n = 0
  void add(const PoseErrorSum& other) { sum_sq += other.sum_sq, n += other.n; }
};

// Dead reckoning of (v, w) over steps [first, end) restarted at the
// ground-truth pose every `window_s` seconds (0: once): each stretch starts
// at its first step with a ground-truth pose and integrates the later steps
// by eq. 3; every later step of the stretch with a ground-truth position
// adds its squared error. `end` is clamped to the track.
PoseErrorSum dead_reckoning_errors(const FusionInput& in, const std::vector<double>& v,
                                   const std::vector<double>& w, double window_s, std::size_t first = 0,
                                   std::size_t end = static_cast<std::size_t>(-1));

// All of a table row. var_* and cov_vw may be empty. The pose is `pose` when
// given (e.g. the UKF's), else dead-reckoned from v, w.
OdometryErrors odometry_errors(const FusionInput& in, const std::vector<double>& v,
                               const std::vector<double>& w, const std::vector<double>& var_v,
                               const std::vector<double>& var_w, const std::vector<double>& cov_vw,
                               const PoseTrack* pose = nullptr);

}  // namespace odotune::learned

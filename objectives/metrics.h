// Position-error metrics against ground truth and the seven fitness modes of
// Kovacs et al. §2.3.4: 1 RMSE, 2 MAE, 3 MAXE, 4 RMSE+MAE, 5 RMSE+MAXE,
// 6 MAE+MAXE, 7 RMSE+MAE+MAXE. All in metres. Modes 8 and 9 (below) need no
// ground truth.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

namespace odotune {

struct ErrorMetrics {
  double rmse_m = 0.0;  // sqrt(mean e²)
  double mae_m = 0.0;   // mean e
  double maxe_m = 0.0;  // max e
  long samples = 0;
};

// Running sums from which ErrorMetrics are made; combine() is associative but
// callers keep a fixed order so results are bit-reproducible.
struct ErrorAccumulator {
  double sum = 0.0, sum_sq = 0.0, max = 0.0;
  long n = 0;
  void add(double e) {
    sum += e;
    sum_sq += e * e;
    max = std::max(max, e);
    ++n;
  }
  ErrorMetrics metrics() const {
    ErrorMetrics m;
    m.samples = n;
    if (n > 0) {
      m.rmse_m = std::sqrt(sum_sq / static_cast<double>(n));
      m.mae_m = sum / static_cast<double>(n);
      m.maxe_m = max;
    }
    return m;
  }
};

inline constexpr int kNumFitnessModes = 7;

// Modes 1..7 score against ground truth.
inline bool valid_fitness_mode(int mode) { return mode >= 1 && mode <= kNumFitnessModes; }

// Modes after the study's seven score an EKF without ground truth, by
// cross-validation over its position fixes (objectives/fix_cv_replay.h):
//   8: RMSE of the held-out fixes' prediction errors [m];
//   9: mean negative log predictive likelihood of the held-out fixes [nats].
inline constexpr int kFixCvRmseMode = 8;
inline constexpr int kFixCvNllMode = 9;
inline constexpr int kNumEkfFitnessModes = 9;
inline bool is_fix_cv_mode(int mode) { return mode == kFixCvRmseMode || mode == kFixCvNllMode; }
// The modes the EKF tune, grid and report take.
inline bool valid_ekf_fitness_mode(int mode) { return valid_fitness_mode(mode) || is_fix_cv_mode(mode); }

// The scalar a fitness mode minimises; mode in 1..7 (checked by the caller).
inline double fitness_of(const ErrorMetrics& m, int mode) {
  switch (mode) {
    case 1: return m.rmse_m;
    case 2: return m.mae_m;
    case 3: return m.maxe_m;
    case 4: return m.rmse_m + m.mae_m;
    case 5: return m.rmse_m + m.maxe_m;
    case 6: return m.mae_m + m.maxe_m;
    default: return m.rmse_m + m.mae_m + m.maxe_m;
  }
}

// Human-readable name of a mode 1..9, e.g. "RMSE+MAE", "held-out fix NLL".
std::string fitness_mode_name(int mode);

// Improvement of `tuned` over `baseline` in percent (positive = better).
inline double improvement_pct(double baseline, double tuned) {
  return baseline > 0.0 ? 100.0 * (baseline - tuned) / baseline : 0.0;
}

}  // namespace odotune

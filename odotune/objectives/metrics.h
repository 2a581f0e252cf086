// Position-error metrics against ground truth and the scalar each of the
// seven fitness modes of Kovacs et al. §2.3.4 makes of them (fitness_mode.h).
// All in metres.
#pragma once

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <odotune/objectives/fitness_mode.h>

namespace odotune::objectives {

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

// The scalar a mode against ground truth minimises [m]; std::logic_error
// for modes 8 and 9, which score fixes (fix_cv_replay.h fix_cv_fitness).
inline double fitness_of(const ErrorMetrics& m, FitnessMode mode) {
  switch (mode) {
    case FitnessMode::rmse: return m.rmse_m;
    case FitnessMode::mae: return m.mae_m;
    case FitnessMode::maxe: return m.maxe_m;
    case FitnessMode::rmse_mae: return m.rmse_m + m.mae_m;
    case FitnessMode::rmse_maxe: return m.rmse_m + m.maxe_m;
    case FitnessMode::mae_maxe: return m.mae_m + m.maxe_m;
    case FitnessMode::rmse_mae_maxe: return m.rmse_m + m.mae_m + m.maxe_m;
    case FitnessMode::fix_rmse:
    case FitnessMode::fix_nll: break;
  }
  throw std::logic_error("fitness_of: mode " + std::to_string(number(mode)) +
                         " scores fixes, not ground truth");
}

// Improvement of `tuned` over `baseline` in percent (positive = better).
inline double improvement_pct(double baseline, double tuned) {
  return baseline > 0.0 ? 100.0 * (baseline - tuned) / baseline : 0.0;
}

}  // namespace odotune::objectives

// The white noise of a pose reference (motion capture, a simulator's noisy
// ground truth) estimated from the reference itself: its second differences
// over consecutive samples, x_{i+1} − 2x_i + x_{i−1}, have variance 6σ² under
// white noise of σ plus the motion's own a·Δt², which is small at motion-
// capture rates and sparse (turns, starts), so a robust scale (the median
// absolute deviation, / 0.6745 for a normal's σ) reads the noise and not the
// motion. Used to set the noise of velocities derived from the reference
// (calibration_input.h, --ext-from-gt) from the data instead of a fixed σ.
#pragma once

#include <cstddef>

#include <odotune/objectives/pose_series.h>

namespace odotune::calibration {

struct ReferenceJitter {
  double sigma_xy_m = 0.0;       // per axis [m] (x and y pooled)
  double sigma_theta_rad = 0.0;  // [rad]
  double median_dt_s = 0.0;      // the reference's median sample spacing [s]
  std::size_t triples = 0;       // second differences used (0: fewer than 3 samples; σ = 0)
};

// Second differences over triples of consecutive samples whose two spacings
// differ by at most 10 % (an uneven triple's second difference is not a pure
// noise term) and are at most 0.5 s.
ReferenceJitter estimate_reference_jitter(const objectives::PoseSeries& reference);

}  // namespace odotune::calibration

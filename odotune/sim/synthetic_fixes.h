// Absolute position fixes made from a track's ground truth, as in Kovacs et
// al. §2.1: "selection" at a fixed frequency from the ground-truth path, then
// "perturbation" with zero-mean Gaussian noise (σ = 60 mm in the study). This
// is how recordings without a positioning system (OptiOdom, MRCLAM, Lost in
// the Woods) become tunable.
#pragma once

#include <cstdint>
#include <string>

#include <odotune/tracks/track.h>

namespace odotune::sim {

struct SyntheticFixOptions {
  double rate_hz = 1.0;    // fix frequency
  double sigma_m = 0.060;  // noise σ per axis [m]
  std::uint64_t seed = 1;  // explicit seed of the noise
  // Also write each fix's variances (aps_var_x, aps_var_y = σ²; none when
  // σ = 0), as a positioning system reports them.
  bool variances = true;

  bool IsValid(std::string* why) const;
};

// A copy of `track` whose aps_x/aps_y columns (replaced if present, with
// aps_var_x/aps_var_y) hold a
// fix at the first ground-truth row at or after each multiple of 1/rate_hz
// from the first ground-truth time (the first fix one period after it). The
// metadata records how the fixes were made. Throws std::invalid_argument when
// the options are invalid or the track has no ground truth.
tracks::Track with_synthetic_fixes(const tracks::Track& track, const SyntheticFixOptions& options);

}  // namespace odotune::sim

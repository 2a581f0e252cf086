#include <odotune/sim/synthetic_fixes.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/why.h>
#include <odotune/sim/normal_rng.h>

namespace odotune::sim {

bool SyntheticFixOptions::IsValid(std::string* why) const {
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0)) {
    return core::invalid(why, fmt::format("rate_hz = {}: expected a finite value > 0", rate_hz));
  }
  if (!(std::isfinite(sigma_m) && sigma_m >= 0.0)) {
    return core::invalid(why, fmt::format("sigma_m = {}: expected a finite value >= 0", sigma_m));
  }
  return true;
}

tracks::Track with_synthetic_fixes(const tracks::Track& track, const SyntheticFixOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("synthetic fixes: " + why);
  if (!track.has_gt())
    throw std::invalid_argument(
        fmt::format("track '{}': no ground truth (gt_x, gt_y) to make position fixes from", track.name()));
  tracks::TrackData d = track.data();
  const std::size_t n = d.t.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  d.col(tracks::Col::aps_x).assign(n, nan);
  d.col(tracks::Col::aps_y).assign(n, nan);
  // The fixes' own variances (σ² per axis), replacing any the track had.
  const bool variances = options.variances && options.sigma_m > 0.0;
  d.col(tracks::Col::aps_var_x).assign(variances ? n : 0, nan);
  d.col(tracks::Col::aps_var_y).assign(variances ? n : 0, nan);
  const auto& gx = d.cols[static_cast<int>(tracks::Col::gt_x)];
  const auto& gy = d.cols[static_cast<int>(tracks::Col::gt_y)];

  Normal noise(splitmix64(options.seed));
  const double period = 1.0 / options.rate_hz;
  double t_first = nan;
  long k = 1;
  long made = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isnan(gx[i]) || std::isnan(gy[i])) continue;
    if (std::isnan(t_first)) {
      t_first = d.t[i];
      continue;
    }
    if (d.t[i] + 1e-9 < t_first + static_cast<double>(k) * period) continue;
    const double ex = options.sigma_m * noise();
    const double ey = options.sigma_m * noise();
    d.col(tracks::Col::aps_x)[i] = gx[i] + ex;
    d.col(tracks::Col::aps_y)[i] = gy[i] + ey;
    if (variances) {
      d.col(tracks::Col::aps_var_x)[i] = options.sigma_m * options.sigma_m;
      d.col(tracks::Col::aps_var_y)[i] = options.sigma_m * options.sigma_m;
    }
    ++made;
    // The next multiple of the period after this row (gaps skip missed ones).
    k = static_cast<long>(std::floor((d.t[i] - t_first) / period + 1e-9)) + 1;
  }
  d.meta.extra.emplace_back("fixes.synthetic",
                            fmt::format("{} fixes from ground truth at {} Hz with sigma {} m, seed {} "
                                        "(Kovacs et al. 2.1: selection then Gaussian perturbation){}",
                                        made, options.rate_hz, options.sigma_m, options.seed,
                                        variances ? "; aps_var_x, aps_var_y = sigma^2" : ""));
  return tracks::Track(std::move(d));
}

}  // namespace odotune::sim

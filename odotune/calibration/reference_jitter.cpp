#include <odotune/calibration/reference_jitter.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <odotune/core/robust_stats.h>

namespace odotune::calibration {

namespace {

constexpr double kMaxSpacingS = 0.5;
constexpr double kMaxUnevenness = 0.1;
// The MAD of a normal sample over its σ.
constexpr double kMadPerSigma = 0.6745;

// Median absolute deviation from the median, as a normal σ (0 for no data):
// upper medians and /0.6745, not core::robust_sigma (mean of the two middle
// values, ×1.4826): the calibration tables were made with this one.
double mad_sigma(std::vector<double> v) {
  return v.empty() ? 0.0 : core::mad(std::move(v), core::MedianRule::upper_middle) / kMadPerSigma;
}

}  // namespace

ReferenceJitter estimate_reference_jitter(const objectives::PoseSeries& ref) {
  ReferenceJitter out;
  const std::size_t n = ref.size();
  if (n < 3) return out;
  std::vector<double> d_xy, d_theta, spacing;
  for (std::size_t i = 1; i < n; ++i) spacing.push_back(ref.t[i] - ref.t[i - 1]);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double a = ref.t[i] - ref.t[i - 1], b = ref.t[i + 1] - ref.t[i];
    if (!(a > 0.0 && b > 0.0 && a <= kMaxSpacingS && b <= kMaxSpacingS)) continue;
    if (std::abs(a - b) > kMaxUnevenness * std::max(a, b)) continue;
    d_xy.push_back(ref.x[i + 1] - 2.0 * ref.x[i] + ref.x[i - 1]);
    d_xy.push_back(ref.y[i + 1] - 2.0 * ref.y[i] + ref.y[i - 1]);
    d_theta.push_back(ref.theta[i + 1] - 2.0 * ref.theta[i] + ref.theta[i - 1]);
  }
  out.triples = d_theta.size();
  // Var(x_{i+1} − 2x_i + x_{i−1}) = (1 + 4 + 1)σ² under white noise.
  const double per_sigma = std::sqrt(6.0);
  out.sigma_xy_m = mad_sigma(std::move(d_xy)) / per_sigma;
  out.sigma_theta_rad = mad_sigma(std::move(d_theta)) / per_sigma;
  out.median_dt_s = core::median_period_s(ref.t, core::MedianRule::upper_middle);
  return out;
}

}  // namespace odotune::calibration

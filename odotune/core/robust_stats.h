// Robust location and scale, written once for every module: the median (also
// of sampling periods and of sorted data), order statistics, and the median
// absolute deviation (MAD), also as a normal σ and as the σ of white noise on a
// smooth signal.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <vector>

namespace odotune::core {

// The median of an even count: the mean of the two middle values, or the
// upper of them (the value of rank n/2, always an observed sample). The
// diagnosis's and the calibration's medians of periods, cells and MADs use the
// upper one, with which their thresholds were chosen; they differ only in the
// last bits for regular samples, but not for cells of a grid.
enum class MedianRule { mean_of_middle, upper_middle };

// The median of values sorted ascending; NaN when empty.
inline double sorted_median(std::span<const double> sorted, MedianRule rule = MedianRule::mean_of_middle) {
  const std::size_t n = sorted.size();
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  if (n % 2 == 1 || rule == MedianRule::upper_middle) return sorted[n / 2];
  return 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
}

// The k-th smallest value (k = 0 is the minimum), e.g. a quantile by rank;
// NaN when k is out of range. O(n): a selection, not a sort.
inline double order_statistic(std::vector<double> v, std::size_t k) {
  if (k >= v.size()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// The median; NaN when empty. O(n).
inline double median(std::vector<double> v, MedianRule rule = MedianRule::mean_of_middle) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  double med = v[m];
  if (v.size() % 2 == 0 && rule == MedianRule::mean_of_middle)
    med = 0.5 * (med + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m)));
  return med;
}

// The median interval between successive times t_s [s] (a recording's
// sampling period, robust to gaps and jitter); NaN with fewer than 2 times.
inline double median_period_s(std::span<const double> t_s, MedianRule rule = MedianRule::mean_of_middle) {
  if (t_s.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> dt(t_s.size() - 1);
  for (std::size_t i = 0; i + 1 < t_s.size(); ++i) dt[i] = t_s[i + 1] - t_s[i];
  return median(std::move(dt), rule);
}

// The median absolute deviation about the median (both medians by `rule`);
// NaN when empty.
inline double mad(std::vector<double> v, MedianRule rule = MedianRule::mean_of_middle) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double med = median(v, rule);
  for (double& x : v) x = std::abs(x - med);
  return median(std::move(v), rule);
}

// 1.4826·MAD: σ of a normal sample, robust to outliers (Hampel 1974). NaN when
// empty.
inline double robust_sigma(const std::vector<double>& v) { return 1.4826 * mad(v); }

// Robust σ of white noise on a sampled signal from its second differences (a
// smooth signal cancels; each difference has variance 6σ²): robust_sigma / √6.
// 0 when there are fewer than three samples.
inline double second_difference_sigma(const std::vector<double>& v) {
  std::vector<double> d2;
  for (std::size_t k = 1; k + 1 < v.size(); ++k) d2.push_back(v[k + 1] - 2.0 * v[k] + v[k - 1]);
  return d2.empty() ? 0.0 : robust_sigma(d2) / std::sqrt(6.0);
}

}  // namespace odotune::core

#include <odotune/diagnose/paired_test.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numeric>

namespace odotune::diagnose {

namespace {
constexpr std::size_t kExactRankMax = 60;  // exact Wilcoxon distribution up to this many values
}  // namespace

double normal_upper_tail(double z) { return 0.5 * std::erfc(z / std::sqrt(2.0)); }

double stouffer_greater(const std::vector<double>& z) {
  if (z.empty()) return std::numeric_limits<double>::quiet_NaN();
  return normal_upper_tail(std::accumulate(z.begin(), z.end(), 0.0) / std::sqrt(static_cast<double>(z.size())));
}

double stouffer_greater_but_strongest(const std::vector<double>& z) {
  if (z.size() < 3) return std::numeric_limits<double>::quiet_NaN();
  const double sum = std::accumulate(z.begin(), z.end(), 0.0) - *std::max_element(z.begin(), z.end());
  return normal_upper_tail(sum / std::sqrt(static_cast<double>(z.size() - 1)));
}

// Regularised incomplete beta I_x(a, b), continued fraction (modified Lentz).
double incomplete_beta(double x, double a, double b) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  if (x > (a + 1.0) / (a + b + 2.0)) return 1.0 - incomplete_beta(1.0 - x, b, a);
  const double front =
      std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x)) / a;
  const double tiny = 1e-300;
  double f = 1.0, cc = 1.0, d = 0.0;
  for (int i = 0; i <= 400; ++i) {
    const int m = i / 2;
    double num = 1.0;
    if (i > 0)
      num = (i % 2 == 0) ? m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m))
                         : -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0));
    d = 1.0 + num * d;
    d = 1.0 / (std::abs(d) < tiny ? tiny : d);
    cc = 1.0 + num / cc;
    if (std::abs(cc) < tiny) cc = tiny;
    f *= cc * d;
    if (std::abs(1.0 - cc * d) < 1e-12) break;
  }
  return front * (f - 1.0);
}

// One-sided p of a one-sample t-test that the mean of v is > 0 (NaN for < 3 values).
double t_test_greater(const std::vector<double>& v) {
  const std::size_t n = v.size();
  if (n < 3) return std::numeric_limits<double>::quiet_NaN();
  double m = 0.0, s = 0.0;
  for (double x : v) m += x;
  m /= static_cast<double>(n);
  for (double x : v) s += (x - m) * (x - m);
  const double df = static_cast<double>(n - 1);
  const double se = std::sqrt(s / df / static_cast<double>(n));
  if (!(se > 0.0)) return m > 0.0 ? 0.0 : 1.0;
  const double t = m / se;
  const double tail = 0.5 * incomplete_beta(df / (df + t * t), 0.5 * df, 0.5);
  return t > 0.0 ? tail : 1.0 - tail;
}

// One-sided p of the Wilcoxon signed-rank test that the d's are centred
// above 0 (zeros must be removed by the caller). Average ranks for ties.
double wilcoxon_greater(const std::vector<double>& d) {
  const std::size_t n = d.size();
  if (n == 0) return 1.0;
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return std::abs(d[a]) < std::abs(d[b]); });
  std::vector<long> r2(n);  // doubled ranks (average ranks of ties are halves)
  for (std::size_t i = 0; i < n;) {
    std::size_t j = i;
    while (j + 1 < n && std::abs(d[order[j + 1]]) == std::abs(d[order[i]])) ++j;
    for (std::size_t k = i; k <= j; ++k) r2[order[k]] = static_cast<long>(i + j + 2);
    i = j + 1;
  }
  long w = 0, total = 0;
  double var = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    total += r2[i];
    var += 0.25 * static_cast<double>(r2[i]) * static_cast<double>(r2[i]);
    if (d[i] > 0.0) w += r2[i];
  }
  if (n > kExactRankMax) {
    const double z = (static_cast<double>(w) - 0.5 * static_cast<double>(total) - 1.0) / std::sqrt(var);
    return normal_upper_tail(z);
  }
  std::vector<double> dist(static_cast<std::size_t>(total) + 1, 0.0);
  dist[0] = 1.0;
  long reach = 0;
  for (std::size_t i = 0; i < n; ++i) {
    reach += r2[i];
    for (long s = reach; s >= 0; --s) {
      const double keep = dist[static_cast<std::size_t>(s)];
      const double add = s >= r2[i] ? dist[static_cast<std::size_t>(s - r2[i])] : 0.0;
      dist[static_cast<std::size_t>(s)] = 0.5 * (keep + add);
    }
  }
  double p = 0.0;
  for (long s = w; s <= total; ++s) p += dist[static_cast<std::size_t>(s)];
  return std::min(1.0, p);
}

PairedComparison paired_windows(const std::vector<WindowPair>& windows, double correlated, double alpha) {
  constexpr double kInformativeDelta2 = 4.0;  // in units of L (header comment)
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PairedComparison out;
  std::vector<double> d, z, lr;
  for (const WindowPair& w : windows) {
    if (!(w.delta2 >= kInformativeDelta2 * correlated)) continue;
    const double dw = w.sse_ref - w.sse_alt;
    d.push_back(dw);
    ++out.changed;
    if (dw > 0.0) ++out.improved;
    const double s2 = std::max(1.0, w.sse_alt / w.components);
    z.push_back(dw / (2.0 * std::sqrt(s2 * correlated * w.delta2)));
    lr.push_back(std::log(std::max(w.sse_ref, 1e-300) / std::max(w.sse_alt, 1e-300)));
  }
  out.p_rank = wilcoxon_greater(d);
  out.p_t = std::min(t_test_greater(z), t_test_greater(lr));  // NaN-safe: min(NaN, NaN) = NaN
  // (fmin: the other when one is NaN, NaN when both are.)
  const double p_all = out.changed >= 2 && out.improved == out.changed ? stouffer_greater(z) : nan;
  out.p_param = std::fmin(p_all, stouffer_greater_but_strongest(z));
  out.significant = out.p_rank < alpha || out.p_t < 0.5 * alpha || out.p_param < alpha;
  return out;
}

}  // namespace odotune::diagnose

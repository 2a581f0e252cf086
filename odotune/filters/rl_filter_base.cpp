#include <odotune/filters/rl_filter_base.h>

#include <algorithm>
#include <cmath>

namespace odotune::filters::rl::detail {

int fused_members(const Measurement& m, int* idx) {
  int n = 0;
  for (int i = 0; i < kStateSize; ++i) {
    if (m.mask[i] && std::isfinite(m.z[i])) idx[n++] = i;
  }
  return n;
}

double positive_variance(double r) { return std::max(std::abs(r), 1e-9); }

void gather(const Measurement& m, int n, const int* idx, double* z, double* R) {
  for (int a = 0; a < n; ++a) {
    z[a] = m.z[idx[a]];
    for (int b = 0; b < n; ++b) R[b * n + a] = m.R(idx[a], idx[b]);
    R[a * n + a] = positive_variance(R[a * n + a]);
  }
}

Cov symmetric(const Cov& a) { return (a + a.transpose()) * 0.5; }

void initialise(const Measurement& m, State& x, Cov& P) {
  for (int i = 0; i < kStateSize; ++i) {
    if (!m.mask[i]) continue;
    x[i] = m.z[i];
    for (int j = 0; j < kStateSize; ++j) {
      if (m.mask[j]) P(i, j) = (m.R(i, j) + m.R(j, i)) * 0.5;
    }
  }
}

}  // namespace odotune::filters::rl::detail

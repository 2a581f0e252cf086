// Sampled signals on strictly increasing times, as the diagnosis reads them:
// linear interpolation with the ends held, and a cumulative quantity (given,
// or the exact integral of a rate's linear interpolant). One copy for every
// step of diagnose/ (input, replay, sensor checks, residual series).
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

namespace odotune::diagnose {

// Linear interpolation of samples (t, v) at time x; the end values are held
// outside [t.front(), t.back()]. t strictly increasing, non-empty.
inline double interp_held(const std::vector<double>& t, const std::vector<double>& v, double x) {
  if (x <= t.front()) return v.front();
  if (x >= t.back()) return v.back();
  const auto j = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), x) - t.begin());
  const double f = (x - t[j - 1]) / (t[j] - t[j - 1]);
  return v[j - 1] + f * (v[j] - v[j - 1]);
}

// A cumulative quantity C(t) on sample times: either given directly (e.g.
// wheel angles; linear between samples) or the exact integral of the linear
// interpolant of a rate signal (trapezoids at the samples, a quadratic in
// between). Clamped to the span outside it (within() says NaN instead).
class Cumulative {
 public:
  Cumulative() = default;
  // `t` (and `r` of of_rates) must outlive the Cumulative; `c` is copied.
  static Cumulative of_values(const std::vector<double>& t, std::vector<double> c) {
    return Cumulative(&t, nullptr, std::move(c));
  }
  static Cumulative of_rates(const std::vector<double>& t, const std::vector<double>& r) {
    std::vector<double> c(t.size(), 0.0);
    for (std::size_t i = 1; i < t.size(); ++i) c[i] = c[i - 1] + 0.5 * (r[i] + r[i - 1]) * (t[i] - t[i - 1]);
    return Cumulative(&t, &r, std::move(c));
  }
  double front_t() const { return t_->front(); }
  double back_t() const { return t_->back(); }
  const std::vector<double>& times() const { return *t_; }

  double at(double t) const {
    const std::vector<double>& tt = *t_;
    if (t <= tt.front()) return c_.front();
    if (t >= tt.back()) return c_.back();
    const std::size_t i = static_cast<std::size_t>(std::upper_bound(tt.begin(), tt.end(), t) - tt.begin()) - 1;
    const double h = tt[i + 1] - tt[i], u = t - tt[i];
    if (r_ == nullptr) return c_[i] + (c_[i + 1] - c_[i]) * (u / h);
    const double slope = ((*r_)[i + 1] - (*r_)[i]) / h;
    return c_[i] + (*r_)[i] * u + 0.5 * slope * u * u;
  }
  // at(t) inside the span, NaN outside it.
  double within(double t) const {
    return t >= front_t() && t <= back_t() ? at(t) : std::numeric_limits<double>::quiet_NaN();
  }

 private:
  Cumulative(const std::vector<double>* t, const std::vector<double>* r, std::vector<double> c)
      : t_(t), r_(r), c_(std::move(c)) {}
  const std::vector<double>* t_ = nullptr;
  const std::vector<double>* r_ = nullptr;  // rates when integrated
  std::vector<double> c_;
};

}  // namespace odotune::diagnose

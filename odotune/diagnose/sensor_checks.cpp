#include <odotune/diagnose/sensor_checks.h>

#include <odotune/core/non_finite.h>
#include <odotune/core/robust_stats.h>
#include <odotune/diagnose/option_rules.h>
#include <odotune/diagnose/series_interp.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <initializer_list>
#include <random>
#include <stdexcept>
#include <string_view>
#include <utility>

#include <fmt/format.h>

namespace odotune::diagnose {
namespace {

using core::kNaN;
constexpr int kMinBins = 10;  // fewer bins: a check is not attempted

bool finite_positive(double x) { return std::isfinite(x) && x > 0.0; }

double median_step(const std::vector<double>& t) { return core::median_period_s(t); }

// Smallest positive step between consecutive samples (an encoder's count
// when the angles are quantised); 0 when the signal never moves.
double min_positive_step(const std::vector<double>& v) {
  double m = std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k < v.size(); ++k) {
    const double d = std::abs(v[k] - v[k - 1]);
    if (d > 0 && d < m) m = d;
  }
  return std::isfinite(m) ? m : 0.0;
}

// Times finite and strictly increasing; each column empty or one value per
// time, finite; the first `required` columns must be present.
void check_series(std::string_view track, std::string_view what, const std::vector<double>& t,
                  std::initializer_list<std::pair<std::string_view, const std::vector<double>*>> cols,
                  std::size_t required) {
  const auto fail = [&](const std::string& msg) {
    throw std::invalid_argument(fmt::format("sensor checks, track '{}': {}", track, msg));
  };
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t[i]) || (i > 0 && !(t[i] > t[i - 1]))) {
      fail(fmt::format("{} time [{}] = {} (expected finite, strictly increasing)", what, i, t[i]));
    }
  }
  std::size_t k = 0;
  for (const auto& [name, col] : cols) {
    if ((k++ >= required && col->empty()) || col->size() == t.size()) continue;
    fail(fmt::format("{} has {} values for {} {} times (expected one per time)", name, col->size(), t.size(),
                     what));
  }
  for (const auto& [name, col] : cols) {
    for (std::size_t i = 0; i < col->size(); ++i) {
      if (!std::isfinite((*col)[i])) fail(fmt::format("{}[{}] is not finite (expected a number)", name, i));
    }
  }
}

void check_sensor_input(const DiagInput& in) {
  check_series(in.track_name, "reference", in.ref_t_s,
               {{"ref_x_m", &in.ref_x_m}, {"ref_y_m", &in.ref_y_m}, {"ref_theta_rad", &in.ref_theta_rad}}, 2);
  check_series(in.track_name, "odometry", in.odo_t_s,
               {{"phi_l_rad", &in.phi_l_rad},
                {"phi_r_rad", &in.phi_r_rad},
                {"v_mps", &in.v_mps},
                {"w_radps", &in.w_radps},
                {"cmd_v_mps", &in.cmd_v_mps},
                {"cmd_w_radps", &in.cmd_w_radps}},
               0);
  check_series(in.track_name, "gyro", in.gyro_t_s, {{"gyro_z_radps", &in.gyro_z_radps}}, 1);
}

// Odometry (or commands) as cumulative distance S(t) [m] and heading Ψ(t) [rad].
struct OdoSignal {
  Cumulative dist, head;
  double mean_v(double t0, double t1) const { return (dist.at(t1) - dist.at(t0)) / (t1 - t0); }
  double mean_w(double t0, double t1) const { return (head.at(t1) - head.at(t0)) / (t1 - t0); }
  // Chord of the dead-reckoned path over [t0, t1] (nominal kinematics,
  // midpoint heading per odometry interval).
  double chord(double t0, double t1) const {
    const std::vector<double>& tt = dist.times();
    auto it = std::upper_bound(tt.begin(), tt.end(), t0);
    double x = 0.0, y = 0.0, psi = 0.0, ta = t0, sa = dist.at(t0), ha = head.at(t0);
    while (ta < t1) {
      const double tb = (it != tt.end() && *it < t1) ? *it++ : t1;
      const double sb = dist.at(tb), hb = head.at(tb);
      const double mid = psi + 0.5 * (hb - ha);
      x += (sb - sa) * std::cos(mid);
      y += (sb - sa) * std::sin(mid);
      psi += hb - ha;
      ta = tb;
      sa = sb;
      ha = hb;
    }
    return std::hypot(x, y);
  }
};

// Moving-block bootstrap: `replicates` index sets of n rows made of blocks of
// `block` consecutive rows.
class BlockBootstrap {
 public:
  BlockBootstrap(std::size_t n, std::size_t block, std::uint64_t seed)
      : n_(n), block_(std::clamp<std::size_t>(block, 1, n)), gen_(seed) {}
  std::vector<std::size_t> next() {
    std::vector<std::size_t> idx;
    idx.reserve(n_ + block_);
    const std::size_t starts = n_ - block_ + 1;
    while (idx.size() < n_) {
      const std::size_t s = static_cast<std::size_t>(gen_() % starts);
      for (std::size_t k = 0; k < block_ && idx.size() < n_; ++k) idx.push_back(s + k);
    }
    return idx;
  }

 private:
  std::size_t n_, block_;
  std::mt19937_64 gen_;
};

// Increment-form regression over consecutive bins (header comment):
// y_k = a·x_k (+ b·u_k) + e_k, cov(e) tridiagonal with 2·level_var +
// var_extra[k] on the diagonal and −level_var beside it.
struct Rows {
  std::vector<double> x, u, y, var_extra;  // u empty: no second regressor
  // Row k shares its first edge sample with row k-1 (so their errors are
  // correlated); 0 after a gap or a skipped bin: the whitening restarts.
  std::vector<std::uint8_t> linked;
  double level_var = 0.0;
  // Appends a row for bin [t0, t1]; linked when t0 is the previous row's t1.
  void add(double t0, double t1, double xk, double yk, double var, double uk = kNaN) {
    linked.push_back(!x.empty() && t0 == last_t1_ ? 1 : 0);
    x.push_back(xk);
    y.push_back(yk);
    var_extra.push_back(var);
    if (!std::isnan(uk)) u.push_back(uk);
    last_t1_ = t1;
  }

 private:
  double last_t1_ = kNaN;
};

struct RobustFit {
  bool ok = false;
  double a = kNaN, b = 0.0;
  std::vector<double> xw, uw, yw, res;  // whitened columns and residuals
};

// Huber IRLS of yw = a·xw (+ b·uw) on whitened columns already in f.
// Written out rather than through Ceres (which the fits use): a one- or
// two-column weighted least squares is a 2 × 2 solve per iteration, and the
// block bootstrap repeats it a few hundred times per check, where setting up
// a ceres::Problem each time would cost more than the whole regression.
void huber_irls(RobustFit& f, const SensorCheckOptions& o) {
  const std::size_t n = f.xw.size();
  const bool two = !f.uw.empty();
  std::vector<double> w(n, 1.0);
  f.res.assign(n, 0.0);
  double a = kNaN, b = 0.0;
  f.ok = false;
  for (int it = 0; it < o.max_irls_iterations; ++it) {
    double sxx = 0, sxu = 0, suu = 0, sxy = 0, suy = 0;
    for (std::size_t k = 0; k < n; ++k) {
      sxx += w[k] * f.xw[k] * f.xw[k];
      sxy += w[k] * f.xw[k] * f.yw[k];
      if (two) {
        sxu += w[k] * f.xw[k] * f.uw[k];
        suu += w[k] * f.uw[k] * f.uw[k];
        suy += w[k] * f.uw[k] * f.yw[k];
      }
    }
    double na = 0, nb = 0;
    if (two) {
      const double det = sxx * suu - sxu * sxu;
      if (!(det > 1e-12 * sxx * suu)) return;
      na = (suu * sxy - sxu * suy) / det;
      nb = (sxx * suy - sxu * sxy) / det;
    } else {
      if (!(sxx > 0)) return;
      na = sxy / sxx;
    }
    const bool converged = it > 0 && std::abs(na - a) <= 1e-12 * (1.0 + std::abs(na)) &&
                           std::abs(nb - b) <= 1e-12 * (1.0 + std::abs(nb));
    a = na;
    b = nb;
    for (std::size_t k = 0; k < n; ++k) f.res[k] = f.yw[k] - a * f.xw[k] - (two ? b * f.uw[k] : 0.0);
    if (converged) break;
    const double c = o.huber_k * std::max(core::robust_sigma(f.res), 1e-300);
    for (std::size_t k = 0; k < n; ++k) w[k] = std::abs(f.res[k]) <= c ? 1.0 : c / std::abs(f.res[k]);
  }
  f.ok = std::isfinite(a) && std::isfinite(b);
  f.a = a;
  f.b = b;
}

RobustFit gls_huber_fit(const Rows& r, const SensorCheckOptions& o) {
  RobustFit f;
  const std::size_t n = r.x.size();
  const bool two = !r.u.empty();
  if (n < 3) return f;
  // Whitened columns: solve L·z = v with L the Cholesky factor of Σ.
  f.xw.resize(n);
  f.yw.resize(n);
  f.uw.resize(two ? n : 0);
  double prev_l = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double diag = 2.0 * r.level_var + r.var_extra[k];
    const double m = k == 0 || !r.linked[k] ? 0.0 : -r.level_var / prev_l;  // sub-diagonal of L
    const double l2 = diag - m * m;
    if (!(l2 > 0)) return f;
    const double l = std::sqrt(l2);
    f.xw[k] = (r.x[k] - (k ? m * f.xw[k - 1] : 0.0)) / l;
    f.yw[k] = (r.y[k] - (k ? m * f.yw[k - 1] : 0.0)) / l;
    if (two) f.uw[k] = (r.u[k] - (k ? m * f.uw[k - 1] : 0.0)) / l;
    prev_l = l;
  }
  huber_irls(f, o);
  return f;
}

// Block residual bootstrap of a GLS fit: the whitened residuals, resampled
// in moving blocks (which keeps any correlation the noise model missed),
// are added back to the fitted whitened values and the fit is repeated.
// Calls `use(fit)` for each successful replicate.
template <class Use>
void bootstrap(const RobustFit& f, std::size_t block, std::uint64_t seed, const SensorCheckOptions& o,
               Use use) {
  BlockBootstrap boot(f.res.size(), block, seed);
  RobustFit b = f;
  for (int r = 0; r < o.bootstrap_replicates; ++r) {
    const std::vector<std::size_t> idx = boot.next();
    for (std::size_t k = 0; k < idx.size(); ++k) {
      b.yw[k] = f.a * f.xw[k] + (f.uw.empty() ? 0.0 : f.b * f.uw[k]) + f.res[idx[k]];
    }
    huber_irls(b, o);
    if (b.ok) use(b);
  }
}

// Robust σ of the rate residuals (y − a·x − b·u)/width of a fit.
double rate_residual_sigma(const Rows& r, const std::vector<double>& width, const RobustFit& f) {
  std::vector<double> res(r.y.size());
  for (std::size_t k = 0; k < res.size(); ++k) {
    res[k] = (r.y[k] - f.a * r.x[k] - (r.u.empty() ? 0.0 : f.b * r.u[k])) / width[k];
  }
  return core::robust_sigma(res);
}

double sample_sd(const std::vector<double>& v) {
  if (v.size() < 2) return kNaN;
  double m = 0;
  for (double x : v) m += x;
  m /= static_cast<double>(v.size());
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

std::vector<std::size_t> iota_idx(std::size_t n) {
  std::vector<std::size_t> idx(n);
  for (std::size_t i = 0; i < n; ++i) idx[i] = i;
  return idx;
}

std::size_t block_rows(const ReferenceBins& rb, const SensorCheckOptions& o) {
  const double mean_w = (rb.t1_s.back() - rb.t0_s.front()) / static_cast<double>(rb.t0_s.size());
  return static_cast<std::size_t>(std::max(1.0, std::round(o.bootstrap_block_s / mean_w)));
}

void finish_verdict(Verdict& v, double floor, const SensorCheckOptions& o) {
  v.z = (v.value - v.noop) / v.std_error;
  v.significant = std::isfinite(v.z) && std::abs(v.z) > o.z_threshold;
  v.relevant = std::isfinite(v.drift) && std::isfinite(v.noise_drift) &&
               v.drift > std::max(o.relevance_factor * v.noise_drift, floor);
}

GyroCheck check_gyro(const DiagInput& in, const ReferenceBins& rb, const SensorCheckOptions& o) {
  GyroCheck g;
  g.scale.name = "gyro_scale.s";
  g.scale.noop = 1.0;
  g.bias.name = "gyro_bias.b";
  g.bias.noop = 0.0;
  if (in.gyro_t_s.size() < 3) return g.unavailable_reason = "no gyro", g;
  if (!rb.heading) return g.unavailable_reason = "no reference heading (position fixes only)", g;
  const Cumulative gyro = Cumulative::of_rates(in.gyro_t_s, in.gyro_z_radps);
  g.noise_sigma_radps = core::second_difference_sigma(in.gyro_z_radps);
  const double dt_gyro = median_step(in.gyro_t_s);
  Rows rows;  // Δθ_ref = α·Δψ_gyro + β·width
  rows.level_var = rb.heading_noise_rad * rb.heading_noise_rad;
  double mabs = 0.0;
  for (std::size_t i = 0; i < rb.t0_s.size(); ++i) {
    const double t0 = rb.t0_s[i], t1 = rb.t1_s[i];
    if (t0 < gyro.front_t() || t1 > gyro.back_t()) continue;
    rows.add(t0, t1, gyro.at(t1) - gyro.at(t0), rb.w_radps[i] * (t1 - t0),
             std::max(g.noise_sigma_radps * g.noise_sigma_radps * dt_gyro * (t1 - t0), 1e-18), t1 - t0);
    mabs += std::abs(rb.w_radps[i]);
  }
  g.bins = static_cast<int>(rows.x.size());
  if (g.bins < kMinBins) return g.unavailable_reason = "too few reference bins within the gyro's span", g;

  const RobustFit f = gls_huber_fit(rows, o);
  if (!f.ok || f.a == 0.0) return g.unavailable_reason = "the reference does not turn (yaw rate constant)", g;
  g.available = true;
  g.scale.value = 1.0 / f.a;
  g.bias.value = -f.b / f.a;
  g.residual_sigma_radps = rate_residual_sigma(rows, rows.u, f);
  g.mean_abs_rate_radps = mabs / g.bins;

  std::vector<double> ss, bs;
  bootstrap(f, block_rows(rb, o), o.seed, o, [&](const RobustFit& fb) {
    if (fb.a == 0.0) return;
    ss.push_back(1.0 / fb.a);
    bs.push_back(-fb.b / fb.a);
  });
  g.scale.std_error = sample_sd(ss);
  g.bias.std_error = sample_sd(bs);

  const double T = o.relevance_window_s;
  const double noise_drift = g.noise_sigma_radps * std::sqrt(T * dt_gyro);
  g.scale.drift = std::abs(g.scale.value - 1.0) * g.mean_abs_rate_radps * T;
  g.bias.drift = std::abs(g.bias.value) * T;
  g.scale.noise_drift = g.bias.noise_drift = noise_drift;
  finish_verdict(g.scale, o.min_drift_rad, o);
  finish_verdict(g.bias, o.min_drift_rad, o);
  return g;
}

// Pearson correlation of (a, b) over rows idx.
double pearson(const std::vector<double>& a, const std::vector<double>& b,
               const std::vector<std::size_t>& idx) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  for (std::size_t i : idx) {
    sa += a[i];
    sb += b[i];
    saa += a[i] * a[i];
    sbb += b[i] * b[i];
    sab += a[i] * b[i];
  }
  const double n = static_cast<double>(idx.size());
  const double va = saa - sa * sa / n, vb = sbb - sb * sb / n, cab = sab - sa * sb / n;
  if (!(va > 0) || !(vb > 0)) return kNaN;
  return cab / std::sqrt(va * vb);
}

struct LagCurves {
  std::vector<double> shifts;              // τ_k [s]
  std::vector<std::vector<double>> sig_v;  // [k][bin] shifted signal speed
  std::vector<std::vector<double>> sig_w;  // [k][bin] shifted signal yaw rate (gt only)
};

struct Peak {
  double lag = kNaN, corr = kNaN;
  bool edge = false;
};

// Peak of the mean correlation over shifts, refined by a parabola.
Peak peak(const LagCurves& c, const std::vector<double>& rv, const std::vector<double>& rw,
          const std::vector<std::size_t>& idx) {
  const std::size_t K = c.shifts.size();
  std::vector<double> rho(K, kNaN);
  std::size_t best = K;
  for (std::size_t k = 0; k < K; ++k) {
    const double a = pearson(rv, c.sig_v[k], idx), b = rw.empty() ? kNaN : pearson(rw, c.sig_w[k], idx);
    rho[k] = std::isfinite(b) ? (std::isfinite(a) ? 0.5 * (a + b) : b) : a;
    if (std::isfinite(rho[k]) && (best == K || rho[k] > rho[best])) best = k;
  }
  Peak p;
  if (best == K) return p;
  p.corr = rho[best];
  p.lag = c.shifts[best];
  p.edge = best == 0 || best + 1 == K;
  if (p.edge) return p;
  const double a = rho[best - 1], b = rho[best], d = rho[best + 1];
  const double den = a - 2.0 * b + d;
  if (std::isfinite(den) && den < 0) {
    const double off = std::clamp(0.5 * (a - d) / den, -0.5, 0.5);
    p.lag += off * (c.shifts[1] - c.shifts[0]);
    p.corr = b - 0.25 * (a - d) * off;
  }
  return p;
}

// Lag of `sig` against the reference bins: corr(ref(bin), sig(bin + τ)) maximal.
LagEstimate estimate_lag(const OdoSignal& sig, const ReferenceBins& rb, double step,
                         const SensorCheckOptions& o) {
  LagEstimate out;
  LagCurves c;
  const int half = static_cast<int>(std::floor(o.max_lag_s / step + 1e-9));
  for (int k = -half; k <= half; ++k) c.shifts.push_back(k * step);
  std::vector<std::size_t> rows;  // bins whose shifted copies stay inside the signal
  std::vector<double> rv, rw;
  for (std::size_t i = 0; i < rb.t0_s.size(); ++i) {
    if (rb.t0_s[i] - o.max_lag_s < sig.dist.front_t() || rb.t1_s[i] + o.max_lag_s > sig.dist.back_t()) continue;
    rows.push_back(i);
    rv.push_back(rb.v_mps[i]);
    if (rb.heading) rw.push_back(rb.w_radps[i]);
  }
  if (rows.size() < static_cast<std::size_t>(kMinBins)) return out;
  c.sig_v.assign(c.shifts.size(), {});
  c.sig_w.assign(c.shifts.size(), {});
  for (std::size_t k = 0; k < c.shifts.size(); ++k) {
    for (std::size_t i : rows) {
      const double t0 = rb.t0_s[i] + c.shifts[k], t1 = rb.t1_s[i] + c.shifts[k];
      c.sig_v[k].push_back(rb.heading ? sig.mean_v(t0, t1) : sig.chord(t0, t1) / (t1 - t0));
      if (rb.heading) c.sig_w[k].push_back(sig.mean_w(t0, t1));
    }
  }
  const Peak p = peak(c, rv, rw, iota_idx(rows.size()));
  out.lag_s = p.lag;
  out.peak_correlation = p.corr;
  out.at_edge = p.edge;
  if (!std::isfinite(out.lag_s)) return out;
  out.available = true;
  std::vector<double> lags;
  BlockBootstrap boot(rows.size(), block_rows(rb, o), o.seed + 1);
  for (int r = 0; r < o.bootstrap_replicates; ++r) {
    const double l = peak(c, rv, rw, boot.next()).lag;
    if (std::isfinite(l)) lags.push_back(l);
  }
  out.std_error_s = sample_sd(lags);
  return out;
}

// The odometry's cumulative travel and heading: from the wheel angles and the
// nominal radii and wheel base, or integrated from body velocities. Returns
// why there is none, "" when there is.
std::string odometry_signal(const DiagInput& in, OdoSignal& odo) {
  if (in.odometry == OdometryKind::wheel_angles) {
    if (in.phi_l_rad.size() < 2 || in.phi_r_rad.size() < 2) return "no wheel angles";
    if (!finite_positive(in.radius_l_m) || !finite_positive(in.radius_r_m) ||
        !finite_positive(in.wheel_base_m)) {
      return "nominal radii / wheel base missing";
    }
    std::vector<double> dist(in.odo_t_s.size()), head(in.odo_t_s.size());
    for (std::size_t i = 0; i < in.odo_t_s.size(); ++i) {
      const double l = in.radius_l_m * in.phi_l_rad[i], r = in.radius_r_m * in.phi_r_rad[i];
      dist[i] = 0.5 * (l + r);
      head[i] = (r - l) / in.wheel_base_m;
    }
    odo = {Cumulative::of_values(in.odo_t_s, std::move(dist)),
           Cumulative::of_values(in.odo_t_s, std::move(head))};
  } else {
    if (in.v_mps.size() < 2 || in.w_radps.size() < 2) return "no body velocities";
    odo = {Cumulative::of_rates(in.odo_t_s, in.v_mps), Cumulative::of_rates(in.odo_t_s, in.w_radps)};
  }
  return "";
}

// The ratio fits' rows over the reference bins within the odometry's span:
// Δs_ref = ratio·Δs_odo (rv) and Δθ_ref = ratio·Δψ_odo (rw), each bin's width,
// and the mean odometry speed, turn rate and bin width (sums until
// OdometryCheck::bins divides them).
struct RatioRows {
  Rows rv, rw;
  std::vector<double> width;
  double mean_abs_v = 0, mean_abs_w = 0, mean_width = 0;
};
RatioRows ratio_rows(const DiagInput& in, const OdoSignal& odo, const ReferenceBins& rb) {
  // Odometry noise per bin (regressor noise of the ratio fits): encoder
  // quantisation, one count = the smallest wheel-angle step seen.
  double var_s = 1e-12, var_h = 1e-12;
  if (in.odometry == OdometryKind::wheel_angles) {
    const double tick = std::min(min_positive_step(in.phi_l_rad), min_positive_step(in.phi_r_rad));
    const double R = 0.5 * (in.radius_l_m + in.radius_r_m);
    var_s = std::max(var_s, R * R * tick * tick / 12.0);
    var_h = std::max(var_h, R * R * tick * tick / (3.0 * in.wheel_base_m * in.wheel_base_m));
  }
  RatioRows q;
  q.rv.level_var = rb.position_noise_m * rb.position_noise_m;
  q.rw.level_var = rb.heading_noise_rad * rb.heading_noise_rad;
  for (std::size_t i = 0; i < rb.t0_s.size(); ++i) {
    const double t0 = rb.t0_s[i], t1 = rb.t1_s[i], dt = t1 - t0;
    if (t0 < odo.dist.front_t() || t1 > odo.dist.back_t()) continue;
    const double ds = rb.heading ? odo.dist.at(t1) - odo.dist.at(t0) : odo.chord(t0, t1);
    q.rv.add(t0, t1, ds, rb.v_mps[i] * dt, var_s);
    q.width.push_back(dt);
    q.mean_abs_v += std::abs(ds) / dt;
    q.mean_width += dt;
    if (rb.heading) {
      const double dh = odo.head.at(t1) - odo.head.at(t0);
      q.rw.add(t0, t1, dh, rb.w_radps[i] * dt, var_h);
      q.mean_abs_w += std::abs(dh) / dt;
    }
  }
  return q;
}

// One ratio's verdict (value, bootstrap standard error, drift against the
// residual noise's over a bin); returns the residual sigma, NaN when the fit
// fails.
double fit_ratio(const Rows& rows, Verdict& v, double mean_abs, double floor, std::uint64_t seed,
                 const RatioRows& q, const ReferenceBins& rb, const SensorCheckOptions& o) {
  const double T = o.relevance_window_s;
  const RobustFit f = gls_huber_fit(rows, o);
  if (!f.ok) return kNaN;
  v.value = f.a;
  std::vector<double> reps;
  bootstrap(f, block_rows(rb, o), seed, o, [&](const RobustFit& fb) { reps.push_back(fb.a); });
  v.std_error = sample_sd(reps);
  const double sigma = rate_residual_sigma(rows, q.width, f);
  v.drift = std::abs(v.value - 1.0) * mean_abs * T;
  v.noise_drift = sigma * q.mean_width;
  finish_verdict(v, floor, o);
  return sigma;
}

// How late the odometry is against the reference, and with commands how far
// the motion trails them.
void set_lags(OdometryCheck& oc, const DiagInput& in, const OdoSignal& odo, const ReferenceBins& rb,
              double mean_width, const SensorCheckOptions& o) {
  const double step = o.lag_step_s > 0 ? o.lag_step_s
                                       : std::max({1e-3, median_step(in.odo_t_s), mean_width / 25.0});
  oc.odometry_late = estimate_lag(odo, rb, step, o);
  if (in.odometry == OdometryKind::wheel_angles && in.cmd_v_mps.size() == in.odo_t_s.size() &&
      in.cmd_w_radps.size() == in.odo_t_s.size()) {
    OdoSignal cmd{Cumulative::of_rates(in.odo_t_s, in.cmd_v_mps),
                  Cumulative::of_rates(in.odo_t_s, in.cmd_w_radps)};
    LagEstimate l = estimate_lag(cmd, rb, step, o);
    l.lag_s = -l.lag_s;  // ref(t) ≈ cmd(t + τ)  ⇔  delay = −τ
    oc.command_delay = l;
  }
}

OdometryCheck check_odometry(const DiagInput& in, const ReferenceBins& rb, const SensorCheckOptions& o) {
  OdometryCheck oc;
  oc.speed_ratio.name = "speed_ratio";
  oc.speed_ratio.noop = 1.0;
  oc.yaw_ratio.name = "yaw_ratio";
  oc.yaw_ratio.noop = 1.0;
  OdoSignal odo;
  if (std::string why = odometry_signal(in, odo); !why.empty()) return oc.unavailable_reason = why, oc;
  RatioRows q = ratio_rows(in, odo, rb);
  oc.bins = static_cast<int>(q.rv.x.size());
  if (oc.bins < kMinBins)
    return oc.unavailable_reason = "too few reference bins within the odometry's span", oc;
  const double nb = static_cast<double>(oc.bins);
  q.mean_abs_v /= nb;
  q.mean_abs_w /= nb;
  q.mean_width /= nb;
  oc.residual_sigma_mps = fit_ratio(q.rv, oc.speed_ratio, q.mean_abs_v, o.min_drift_m, o.seed + 2, q, rb, o);
  if (rb.heading) fit_ratio(q.rw, oc.yaw_ratio, q.mean_abs_w, o.min_drift_rad, o.seed + 3, q, rb, o);
  oc.available = std::isfinite(oc.speed_ratio.value);
  if (!oc.available) return oc.unavailable_reason = "the odometry does not move", oc;
  set_lags(oc, in, odo, rb, q.mean_width, o);
  return oc;
}

}  // namespace

bool SensorCheckOptions::IsValid(std::string* why) const {
  return check_option_rules(
      {
          {is_positive(bin_s), "bin_s", bin_s, "> 0"},
          {is_positive(gyro_bin_s), "gyro_bin_s", gyro_bin_s, "> 0"},
          {is_non_negative(aps_min_bin_s), "aps_min_bin_s", aps_min_bin_s, ">= 0"},
          {is_positive(huber_k), "huber_k", huber_k, "> 0"},
          {max_irls_iterations >= 1 && max_irls_iterations <= 10000, "max_irls_iterations",
           static_cast<double>(max_irls_iterations), "in [1, 10000]"},
          {bootstrap_replicates >= 2 && bootstrap_replicates <= 100000, "bootstrap_replicates",
           static_cast<double>(bootstrap_replicates), "in [2, 100000]"},
          {is_positive(bootstrap_block_s), "bootstrap_block_s", bootstrap_block_s, "> 0"},
          {is_positive(z_threshold), "z_threshold", z_threshold, "> 0"},
          {is_positive(relevance_window_s), "relevance_window_s", relevance_window_s, "> 0"},
          {is_non_negative(relevance_factor), "relevance_factor", relevance_factor, ">= 0"},
          {is_non_negative(min_drift_rad), "min_drift_rad", min_drift_rad, ">= 0"},
          {is_non_negative(min_drift_m), "min_drift_m", min_drift_m, ">= 0"},
          {is_non_negative(max_lag_s) && max_lag_s <= 10, "max_lag_s", max_lag_s, "in [0, 10]"},
          {is_non_negative(lag_step_s), "lag_step_s", lag_step_s, ">= 0 (0 = auto)"},
          {!(lag_step_s > 0 && max_lag_s / lag_step_s > 5000), "lag_step_s", lag_step_s,
           ">= max_lag_s / 5000 (at most 10001 lags)"},
      },
      why);
}

ReferenceBins reference_bins(const DiagInput& in, const SensorCheckOptions& o, double t_begin_s,
                             double t_end_s) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("sensor check options: " + why);
  check_sensor_input(in);
  ReferenceBins rb;
  rb.heading = in.reference == ReferenceKind::gt && in.ref_theta_rad.size() == in.ref_t_s.size();
  const double width = rb.heading ? o.bin_s : std::max(o.bin_s, o.aps_min_bin_s);
  const auto& t = in.ref_t_s;
  // A gap of the reference: a step between two samples longer than this. No
  // bin spans one (header comment, "Gaps").
  const double gap_s = std::max(2.0 * width, 5.0 * median_step(t));
  std::size_t i = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), t_begin_s) - t.begin());
  while (i < t.size()) {
    std::size_t j = i + 1;
    while (j < t.size() && t[j] - t[i] < width * (1.0 - 1e-9) && !(t[j] - t[j - 1] > gap_s)) ++j;
    if (j >= t.size() || t[j] > t_end_s) break;
    if (t[j] - t[j - 1] > gap_s) {  // the next bin starts after the gap
      i = j;
      continue;
    }
    const double dt = t[j] - t[i], dx = in.ref_x_m[j] - in.ref_x_m[i], dy = in.ref_y_m[j] - in.ref_y_m[i];
    rb.t0_s.push_back(t[i]);
    rb.t1_s.push_back(t[j]);
    if (rb.heading) {
      const double mid = 0.5 * (in.ref_theta_rad[i] + in.ref_theta_rad[j]);
      const double half = 0.5 * (in.ref_theta_rad[j] - in.ref_theta_rad[i]);
      const double sinc = std::abs(half) < 1e-4 ? 1.0 - half * half / 6.0 : std::sin(half) / half;
      rb.v_mps.push_back((dx * std::cos(mid) + dy * std::sin(mid)) / (dt * sinc));
      rb.w_radps.push_back(2.0 * half / dt);
    } else {
      rb.v_mps.push_back(std::hypot(dx, dy) / dt);
    }
    i = j;
  }
  // Noise of the reference levels (see the header).
  if (rb.heading) {
    rb.heading_noise_rad = core::second_difference_sigma(in.ref_theta_rad);
    rb.position_noise_m = in.ref_sigma_m > 0
                              ? in.ref_sigma_m
                              : std::sqrt(0.5 * (std::pow(core::second_difference_sigma(in.ref_x_m), 2) +
                                                 std::pow(core::second_difference_sigma(in.ref_y_m), 2)));
  } else {
    rb.position_noise_m = std::max(in.ref_sigma_m, 0.0);
  }
  return rb;
}

SensorCheck check_sensors(const DiagInput& in, const SensorCheckOptions& options) {
  SensorCheck out;
  out.reference = reference_bins(in, options);  // validates options and input
  // The gyro's own, finer bins (header comment, gyro_bin_s).
  SensorCheckOptions g = options;
  const double dt_gyro = in.gyro_t_s.size() >= 2 ? median_step(in.gyro_t_s) : 0.0;
  g.bin_s = std::min(options.bin_s, std::max(options.gyro_bin_s, 2.0 * dt_gyro));
  out.gyro = check_gyro(in, g.bin_s < options.bin_s ? reference_bins(in, g) : out.reference, options);
  out.odometry = check_odometry(in, out.reference, options);
  return out;
}

}  // namespace odotune::diagnose

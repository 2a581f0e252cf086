#include <odotune/diagnose/gyro_fixes_check.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <fmt/format.h>

#include <odotune/core/ceres_options.h>
#include <odotune/core/non_finite.h>
#include <odotune/core/robust_stats.h>
#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>
#include <odotune/diagnose/gyro_dead_reckoning.h>
#include <odotune/diagnose/option_rules.h>
#include <odotune/diagnose/paired_test.h>
#include <odotune/diagnose/series_interp.h>
#include <odotune/diagnose/window_replay.h>

namespace odotune::diagnose {
namespace {

using core::kNaN;
constexpr std::size_t kMinFixes = 3;  // scored fixes a free-anchor window needs
constexpr int kMinWindows = 3;        // used windows the check needs (>= 2 train + 1 held out)
constexpr double kDistanceScaleLo = 0.5, kDistanceScaleHi = 1.5;
constexpr double kStillTravelM = 1e-12;      // rim travel of a still wheel over an interval [m]
constexpr double kMinGyroSigmaRadps = 1e-5;  // floor of the gyro's white noise [rad/s]

// e -> e*sqrt(rho(u)/u), u = |e|^2 (robust loss on a fix's 2D error).
template <typename T>
T robust_weight(const T& u, RobustLoss loss, double c) {
  using std::log;
  using std::sqrt;
  const double c2 = c * c;
  if (loss == RobustLoss::huber) {
    if (scalar(u) <= c2) return T(1.0);
    return sqrt((2.0 * c * sqrt(u) - c2) / u);
  }
  if (loss == RobustLoss::cauchy) {
    if (scalar(u) < 1e-6 * c2) return sqrt(1.0 - 0.5 * u / c2);
    return sqrt(c2 * log(1.0 + u / c2) / u);
  }
  return T(1.0);
}

// A standstill run: both wheels still over [t0, t1]; the gyro's mean there
// is b (plus noise of standard deviation sigma).
struct Standstill {
  double t0_s = 0.0, t1_s = 0.0;
  double mean_radps = 0.0;  // (G(t1) - G(t0))/(t1 - t0)
  double sigma_radps = 0.0;
  int window = -1;  // the used window it belongs to
};

struct Context {
  const DiagInput* in = nullptr;
  GyroDrSeries series;
  std::vector<Window> windows;  // make_windows
  double inv_sigma = 1.0;
  RobustLoss loss = RobustLoss::huber;
  double loss_scale = 3.0;
  double s_lo = 0.5, s_hi = 1.5, b_lo = -1.0, b_hi = 1.0;  // the effect table's ranges
  std::vector<Standstill> still;                           // standstill runs (header comment)
};

// Cost of one window: parameter blocks {s, b, q} and the anchor {x0, y0, theta0}.
class GyroWindowCost {
 public:
  GyroWindowCost(const Context* c, const Window& w) : c_(c), w_(w) {}
  int num_residuals() const { return static_cast<int>(2 * (w_.ref_end - w_.ref_begin)); }

  template <typename T>
  bool operator()(const T* gyro, const T* anchor, T* res) const {
    const std::size_t n = w_.ref_end - w_.ref_begin;
    std::vector<T> px(n), py(n);
    gyro_replay(c_->series, w_, c_->in->ref_t_s, GyroParams<T>{gyro[0], gyro[1], gyro[2]},
                Pose<T>{anchor[0], anchor[1], anchor[2]}, px.data(), py.data());
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t g = w_.ref_begin + i;
      const T ex = (px[i] - c_->in->ref_x_m[g]) * c_->inv_sigma;
      const T ey = (py[i] - c_->in->ref_y_m[g]) * c_->inv_sigma;
      const T wt = robust_weight(T(ex * ex + ey * ey), c_->loss, c_->loss_scale);
      res[2 * i] = ex * wt;
      res[2 * i + 1] = ey * wt;
    }
    return true;
  }

 private:
  const Context* c_;
  Window w_;
};

// Cost of one standstill run on the gyro block {s, b, q}: (mean - b)/sigma.
class StillCost {
 public:
  StillCost(const Context* c, const Standstill& r) : c_(c), r_(r) {}
  template <typename T>
  bool operator()(const T* gyro, T* res) const {
    const T e = (r_.mean_radps - gyro[1]) / r_.sigma_radps;
    res[0] = e * robust_weight(T(e * e), c_->loss, c_->loss_scale);
    return true;
  }

 private:
  const Context* c_;
  Standstill r_;
};

// A window replayed with closed-form anchor: predictions and normalised SSE.
struct Aligned {
  Pose<double> anchor{};
  std::vector<double> px, py;
  double sse = 0.0;  // sum |pred - fix|^2 / sigma^2
};

Aligned replay_aligned(const Context& c, const Window& w, const GyroParams<double>& gp) {
  Aligned a;
  const std::size_t n = w.ref_end - w.ref_begin;
  a.px.resize(n);
  a.py.resize(n);
  a.anchor = {c.in->ref_x_m[w.ref_begin], c.in->ref_y_m[w.ref_begin], 0.0};
  gyro_replay(c.series, w, c.in->ref_t_s, gp, a.anchor, a.px.data(), a.py.data());
  a.anchor = align_rigid(a.anchor, a.px, a.py, *c.in, w);
  gyro_replay(c.series, w, c.in->ref_t_s, gp, a.anchor, a.px.data(), a.py.data());
  for (std::size_t i = 0; i < n; ++i) {
    const double ex = (a.px[i] - c.in->ref_x_m[w.ref_begin + i]) * c.inv_sigma;
    const double ey = (a.py[i] - c.in->ref_y_m[w.ref_begin + i]) * c.inv_sigma;
    a.sse += ex * ex + ey * ey;
  }
  return a;
}

struct Solution {
  std::array<double, 3> gyro{1.0, 0.0, 1.0};   // s, b, q
  std::vector<std::array<double, 3>> anchors;  // per window of the fit, in order
  bool converged = false;
  // Model-based standard errors of s, b, q (Gauss-Newton, residual variance
  // factor 2*cost/(m - n)); NaN when not asked, q not fitted or rank deficient.
  std::array<double, 3> model_se{kNaN, kNaN, kNaN};
};

// Gauss-Newton standard errors of the first `k` Jacobian columns (the gyro
// block's tangent: s, b[, q]) at the current parameters of `problem`,
// parameter blocks in the order `blocks`. Judged on J'J scaled to a unit
// diagonal (so that units do not matter): a smallest eigenvalue below 1e-10
// of the largest counts as rank deficient (NaN).
std::array<double, 3> model_standard_errors(ceres::Problem& problem, const std::vector<double*>& blocks,
                                            int k) {
  std::array<double, 3> se{kNaN, kNaN, kNaN};
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = blocks;
  double cost = 0.0;
  ceres::CRSMatrix j;
  if (!problem.Evaluate(eo, &cost, nullptr, nullptr, &j)) return se;
  const int n = j.num_cols, m = j.num_rows;
  if (m <= n) return se;
  Eigen::MatrixXd jtj = Eigen::MatrixXd::Zero(n, n);
  for (int r = 0; r < m; ++r) {
    const auto lo = static_cast<std::size_t>(j.rows[static_cast<std::size_t>(r)]);
    const auto hi = static_cast<std::size_t>(j.rows[static_cast<std::size_t>(r) + 1]);
    for (std::size_t a = lo; a < hi; ++a)
      for (std::size_t b = lo; b < hi; ++b) jtj(j.cols[a], j.cols[b]) += j.values[a] * j.values[b];
  }
  const Eigen::VectorXd d = jtj.diagonal();
  if (!(d.array() > 0.0).all() || !d.allFinite()) return se;
  const Eigen::VectorXd inv = d.array().rsqrt();
  const Eigen::MatrixXd scaled = inv.asDiagonal() * jtj * inv.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(scaled);
  const Eigen::VectorXd& ev = es.eigenvalues();
  if (!(ev.minCoeff() > 1e-10 * ev.maxCoeff())) return se;
  const Eigen::MatrixXd cov_scaled = es.eigenvectors() * ev.cwiseInverse().asDiagonal() *
                                     es.eigenvectors().transpose();
  const double s2 = 2.0 * cost / static_cast<double>(m - n);
  for (int i = 0; i < k && i < 3; ++i)
    se[static_cast<std::size_t>(i)] = std::sqrt(cov_scaled(i, i) * inv(i) * inv(i) * s2);
  return se;
}

// Fits s, b (and q) with one free anchor per window of `which` (indices into
// c.windows), starting from `start` (anchors: one per entry of `which`).
Solution solve(const Context& c, const std::vector<int>& which, const Solution& start,
               const GyroFixesOptions& o, bool model_se = false) {
  Solution sol = start;
  ceres::Problem problem;
  for (std::size_t i = 0; i < which.size(); ++i) {
    const Window& w = c.windows[static_cast<std::size_t>(which[i])];
    auto* functor = new GyroWindowCost(&c, w);
    const int m = functor->num_residuals();
    auto* cost = new ceres::AutoDiffCostFunction<GyroWindowCost, ceres::DYNAMIC, 3, 3>(functor, m);
    problem.AddResidualBlock(cost, nullptr, sol.gyro.data(), sol.anchors[i].data());
  }
  for (const Standstill& r : c.still) {
    if (std::find(which.begin(), which.end(), r.window) == which.end()) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<StillCost, 1, 3>(new StillCost(&c, r)), nullptr,
                             sol.gyro.data());
  }
  double* g = sol.gyro.data();
  problem.SetParameterLowerBound(g, 0, c.s_lo);
  problem.SetParameterUpperBound(g, 0, c.s_hi);
  problem.SetParameterLowerBound(g, 1, c.b_lo);
  problem.SetParameterUpperBound(g, 1, c.b_hi);
  if (o.fit_distance_scale) {
    problem.SetParameterLowerBound(g, 2, kDistanceScaleLo);
    problem.SetParameterUpperBound(g, 2, kDistanceScaleHi);
  } else {
    g[2] = 1.0;
    problem.SetManifold(g, new ceres::SubsetManifold(3, {2}));
  }
  const ceres::Solver::Options so = core::deterministic_solver_options(o.max_iterations,
                                                                       core::FitTolerance::diagnosis);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  sol.converged = summary.termination_type == ceres::CONVERGENCE;
  if (model_se) {
    std::vector<double*> blocks = {g};
    for (auto& a : sol.anchors) blocks.push_back(a.data());
    sol.model_se = model_standard_errors(problem, blocks, o.fit_distance_scale ? 3 : 2);
  }
  return sol;
}

// Times finite and strictly increasing, each column one finite value per time.
void check_times(std::string_view track, std::string_view what, const std::vector<double>& t,
                 std::initializer_list<std::pair<std::string_view, const std::vector<double>*>> cols) {
  const auto fail = [&](const std::string& msg) {
    throw std::invalid_argument(fmt::format("gyro fixes check, track '{}': {}", track, msg));
  };
  for (std::size_t i = 0; i < t.size(); ++i)
    if (!std::isfinite(t[i]) || (i > 0 && !(t[i] > t[i - 1])))
      fail(fmt::format("{} time [{}] = {} (expected finite, strictly increasing)", what, i, t[i]));
  for (const auto& [name, col] : cols) {
    if (col->size() != t.size())
      fail(fmt::format("{} has {} values for {} {} times (expected one per time)", name, col->size(), t.size(),
                       what));
    for (std::size_t i = 0; i < col->size(); ++i)
      if (!std::isfinite((*col)[i])) fail(fmt::format("{}[{}] is not finite (expected a number)", name, i));
  }
}

// Held-out comparison of `alt` against `ref` (header comment).
HeldoutComparison compare(const Context& c, const std::vector<int>& held, const GyroParams<double>& ref,
                          const GyroParams<double>& alt, std::string what, const GyroFixesOptions& o) {
  HeldoutComparison h;
  h.what = std::move(what);
  double sum_ref = 0, sum_alt = 0, sum_z = 0;
  std::size_t n_all = 0;
  for (int wi : held) {
    const Window& w = c.windows[static_cast<std::size_t>(wi)];
    const Aligned a = replay_aligned(c, w, ref), b = replay_aligned(c, w, alt);
    const std::size_t n = a.px.size();
    sum_ref += a.sse;
    sum_alt += b.sse;
    n_all += n;
    double dd = 0, sse_ref = a.sse, sse_alt = b.sse, terms = 2.0 * static_cast<double>(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double dx = (b.px[i] - a.px[i]) * c.inv_sigma, dy = (b.py[i] - a.py[i]) * c.inv_sigma;
      dd += dx * dx + dy * dy;
    }
    for (const Standstill& r : c.still) {  // the window's standstill means, as samples of b
      if (r.window != wi) continue;
      const double er = (r.mean_radps - ref.b) / r.sigma_radps, ea = (r.mean_radps - alt.b) / r.sigma_radps;
      const double dr = (alt.b - ref.b) / r.sigma_radps;
      sse_ref += er * er;
      sse_alt += ea * ea;
      dd += dr * dr;
      terms += 1.0;
    }
    ++h.windows;
    if (!(dd >= o.min_informative)) continue;
    ++h.informative;
    if (sse_alt < sse_ref) ++h.improved;
    const double sw = std::sqrt(std::max(1.0, sse_alt / terms));
    sum_z += (sse_ref - sse_alt) / (2.0 * sw * std::sqrt(dd));
  }
  const double sigma = 1.0 / c.inv_sigma;
  if (n_all > 0) {
    h.ref_pos_rmse_m = sigma * std::sqrt(sum_ref / static_cast<double>(n_all));
    h.alt_pos_rmse_m = sigma * std::sqrt(sum_alt / static_cast<double>(n_all));
  }
  if (h.informative > 0) {
    h.z = sum_z / std::sqrt(static_cast<double>(h.informative));
    h.p = normal_upper_tail(h.z);
    h.passed = h.p < o.alpha;
  }
  return h;
}

// Pooled in-sample position RMSE [m] of windows `which` with closed-form anchors.
double pooled_rmse(const Context& c, const std::vector<int>& which, const GyroParams<double>& gp) {
  double sse = 0;
  std::size_t n = 0;
  for (int wi : which) {
    const Aligned a = replay_aligned(c, c.windows[static_cast<std::size_t>(wi)], gp);
    sse += a.sse;
    n += a.px.size();
  }
  return n ? std::sqrt(sse / static_cast<double>(n)) / c.inv_sigma : kNaN;
}

// Jackknife standard error of delete-one estimates v: sqrt((n-1)/n * sum (v_i - mean)^2).
double jackknife_se(const std::vector<double>& v) {
  const double n = static_cast<double>(v.size());
  if (v.size() < 2) return kNaN;
  double m = 0, ss = 0;
  for (double x : v) m += x / n;
  for (double x : v) ss += (x - m) * (x - m);
  return std::sqrt((n - 1.0) / n * ss);
}

void check_input(const DiagInput& in) {
  check_times(in.track_name, "reference", in.ref_t_s, {{"ref_x_m", &in.ref_x_m}, {"ref_y_m", &in.ref_y_m}});
  check_times(in.track_name, "gyro", in.gyro_t_s, {{"gyro_z_radps", &in.gyro_z_radps}});
  check_times(in.track_name, "odometry", in.odo_t_s, {});
  if (!(std::isfinite(in.ref_sigma_m) && in.ref_sigma_m > 0))
    throw std::invalid_argument(fmt::format("gyro fixes check, track '{}': ref_sigma_m = {} (expected > 0)",
                                            in.track_name, in.ref_sigma_m));
}

// Fills c (bounds, nominal distance, gyro integral, windows) and marks the
// odometry intervals where both wheels are still. Returns why the input
// cannot be used, or "".
std::string prepare(const DiagInput& in, const GyroFixesOptions& o, Context& c,
                    std::vector<bool>& still_interval) {
  c.in = &in;
  c.inv_sigma = 1.0 / in.ref_sigma_m;
  c.loss = o.loss;
  c.loss_scale = o.loss_scale;
  for (const ParamSlot& p : param_layout(EffectSet().enable(Effect::gyro_scale).enable(Effect::gyro_bias))) {
    if (p.effect == Effect::gyro_scale) {
      c.s_lo = p.lower;
      c.s_hi = p.upper;
    }
    if (p.effect == Effect::gyro_bias) {
      c.b_lo = p.lower;
      c.b_hi = p.upper;
    }
  }
  try {  // the nominal distance: the model without effects (both odometry kinds)
    const EffectModel nominal(in, EffectSet(), o.model);
    const OdoSeries& d = nominal.series();
    const std::size_t n = d.t_s.size();
    c.series.t = d.t_s;
    c.series.s.resize(n);
    for (std::size_t k = 0; k < n; ++k) c.series.s[k] = 0.5 * (d.s_l_m[k] + d.s_r_m[k]);
    still_interval.assign(n - 1, false);
    for (std::size_t k = 0; k + 1 < n; ++k)
      still_interval[k] = std::abs(d.s_l_m[k + 1] - d.s_l_m[k]) <= kStillTravelM &&
                          std::abs(d.s_r_m[k + 1] - d.s_r_m[k]) <= kStillTravelM;
  } catch (const std::invalid_argument& e) {
    return std::string("no wheel distance: ") + e.what();
  }
  const Cumulative gi = Cumulative::of_rates(in.gyro_t_s, in.gyro_z_radps);
  c.series.g.resize(c.series.t.size());
  for (std::size_t k = 0; k < c.series.t.size(); ++k) c.series.g[k] = gi.within(c.series.t[k]);
  c.windows = make_windows(in, o.window_s);
  if (c.windows.size() >= 2) {  // a short last window joins the one before (header comment)
    const Window last = c.windows.back();
    if (last.t_end_s - last.t_begin_s < 0.5 * o.window_s) {
      c.windows.pop_back();
      Window& prev = c.windows.back();
      prev.t_end_s = last.t_end_s;
      prev.node_end = last.node_end;
      prev.ref_end = last.ref_end;
    }
  }
  return "";
}

// The used windows (header comment), with the closed-form anchor of the
// nominal gyro dead reckoning of each; the others go to `skipped`.
std::vector<int> select_windows(const Context& c, const GyroFixesOptions& o, std::vector<Pose<double>>& anchors,
                                std::vector<int>& skipped) {
  std::vector<int> used;
  for (const Window& w : c.windows) {
    const bool inside = std::isfinite(c.series.g[w.node_begin]) && std::isfinite(c.series.g[w.node_end]);
    if (!inside || w.ref_end - w.ref_begin < kMinFixes || w.node_end <= w.node_begin) {
      skipped.push_back(w.index);
      continue;
    }
    const Aligned a = replay_aligned(c, w, {1.0, 0.0, 1.0});
    const double n = static_cast<double>(a.px.size());
    double mx = 0, my = 0, sp = 0;
    for (std::size_t i = 0; i < a.px.size(); ++i) {
      mx += a.px[i] / n;
      my += a.py[i] / n;
    }
    for (std::size_t i = 0; i < a.px.size(); ++i) sp += std::pow(a.px[i] - mx, 2) + std::pow(a.py[i] - my, 2);
    if (std::sqrt(sp / n) < o.min_spread_sigmas / c.inv_sigma) {
      skipped.push_back(w.index);
      continue;
    }
    used.push_back(w.index);
    anchors.push_back(a.anchor);
  }
  return used;
}

// Standstill runs (header comment), each given to the used window holding
// (else nearest to) its middle.
std::vector<Standstill> standstill_runs(const Context& c, const GyroFixesOptions& o,
                                        const std::vector<bool>& still_interval, const std::vector<int>& used,
                                        double gyro_sigma_radps, double dt_gyro_s) {
  std::vector<Standstill> runs;
  const Cumulative gi = Cumulative::of_rates(c.in->gyro_t_s, c.in->gyro_z_radps);
  const auto& t = c.series.t;
  for (std::size_t k = 0; k < still_interval.size();) {
    if (!still_interval[k]) {
      ++k;
      continue;
    }
    std::size_t e = k;
    while (e < still_interval.size() && still_interval[e]) ++e;
    Standstill r;
    r.t0_s = t[k] + o.standstill_trim_s;
    r.t1_s = t[e] - o.standstill_trim_s;
    k = e;
    const double dur = r.t1_s - r.t0_s, g0 = gi.within(r.t0_s), g1 = gi.within(r.t1_s);
    if (!(dur >= o.min_standstill_s) || !std::isfinite(g0) || !std::isfinite(g1)) continue;
    r.mean_radps = (g1 - g0) / dur;
    r.sigma_radps = std::max(gyro_sigma_radps, kMinGyroSigmaRadps) * std::sqrt(dt_gyro_s / dur);
    const double mid = 0.5 * (r.t0_s + r.t1_s);
    double best = std::numeric_limits<double>::infinity();
    for (int wi : used) {
      const Window& w = c.windows[static_cast<std::size_t>(wi)];
      const double d = mid < w.t_begin_s ? w.t_begin_s - mid : mid >= w.t_end_s ? mid - w.t_end_s : 0.0;
      if (d < best) {
        best = d;
        r.window = wi;
      }
    }
    runs.push_back(r);
  }
  return runs;
}

// Mean |corrected gyro rate| [rad/s] over the span of the used windows.
double mean_abs_rate(const Context& c, const std::vector<int>& used, const GyroParams<double>& gp) {
  const double t0 = c.windows[static_cast<std::size_t>(used.front())].t_begin_s;
  const double t1 = c.windows[static_cast<std::size_t>(used.back())].t_end_s;
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < c.in->gyro_t_s.size(); ++i)
    if (c.in->gyro_t_s[i] >= t0 && c.in->gyro_t_s[i] <= t1) {
      sum += std::abs(corrected_gyro_rate(c.in->gyro_z_radps[i], gp.b, gp.s));
      ++n;
    }
  return n ? sum / static_cast<double>(n) : kNaN;
}

// Delete-one-window refits (warm-started from `all`): s, b, q of each.
std::array<std::vector<double>, 3> jackknife(const Context& c, const std::vector<int>& used,
                                             const Solution& all, const GyroFixesOptions& o) {
  std::array<std::vector<double>, 3> out;
  for (std::size_t drop = 0; drop < used.size(); ++drop) {
    std::vector<int> which;
    Solution start;
    start.gyro = all.gyro;
    for (std::size_t i = 0; i < used.size(); ++i) {
      if (i == drop) continue;
      which.push_back(used[i]);
      start.anchors.push_back(all.anchors[i]);
    }
    const Solution s = solve(c, which, start, o);
    for (std::size_t j = 0; j < 3; ++j) out[j].push_back(s.gyro[j]);
  }
  return out;
}

// The options as run: a track too short for kMinWindows windows of window_s
// gets shorter ones, down to min_window_s (header comment).
GyroFixesOptions options_for_track(const DiagInput& in, const GyroFixesOptions& options) {
  GyroFixesOptions o = options;
  if (in.ref_t_s.size() >= 2) {
    const double span = in.ref_t_s.back() - in.ref_t_s.front();
    if (span < kMinWindows * o.window_s)
      o.window_s = std::max(std::min(o.window_s, o.min_window_s), span / kMinWindows);
  }
  return o;
}

// Gyro noise (per sample), period, standstill runs (into c.still and out);
// returns the gyro's median sample period [s].
double gyro_noise_and_standstill(const DiagInput& in, const GyroFixesOptions& o, Context& c,
                                 const std::vector<bool>& still_interval, const std::vector<int>& used,
                                 GyroFixesCheck& out) {
  GyroCheck& g = out.gyro;
  g.noise_sigma_radps = core::second_difference_sigma(in.gyro_z_radps);
  const double dt_gyro = core::median_period_s(in.gyro_t_s);
  if (o.use_standstill && in.odometry == OdometryKind::wheel_angles)
    c.still = standstill_runs(c, o, still_interval, used, g.noise_sigma_radps, dt_gyro);
  out.standstill_runs = static_cast<int>(c.still.size());
  for (const Standstill& r : c.still) out.standstill_s += r.t1_s - r.t0_s;
  return dt_gyro;
}

// A fit's start on windows `which`: the nominal gyro and each window's
// closed-form anchor (`start_anchor`, in the order of `used`).
Solution start_for(const std::vector<int>& used, const std::vector<Pose<double>>& start_anchor,
                   const std::vector<int>& which) {
  Solution s;
  for (int wi : which) {
    const auto it = std::find(used.begin(), used.end(), wi);
    const Pose<double>& a = start_anchor[static_cast<std::size_t>(it - used.begin())];
    s.anchors.push_back({a.x, a.y, a.th});
  }
  return s;
}

// All-window fit, with its model-based standard errors, and its errors
// against nominal.
Solution fit_all_windows(const Context& c, const std::vector<int>& used,
                         const std::vector<Pose<double>>& start_anchor, const GyroFixesOptions& o,
                         GyroFixesCheck& out) {
  GyroCheck& g = out.gyro;
  Solution all = solve(c, used, start_for(used, start_anchor, used), o, true);
  ++out.fits;
  out.converged = all.converged;
  const GyroParams<double> noop{1.0, 0.0, 1.0}, fitted{all.gyro[0], all.gyro[1], all.gyro[2]};
  g.available = true;
  g.scale.value = fitted.s;
  g.bias.value = fitted.b;
  out.distance_scale = fitted.q;
  out.nominal_pos_rmse_m = pooled_rmse(c, used, noop);
  out.fitted_pos_rmse_m = pooled_rmse(c, used, fitted);
  g.mean_abs_rate_radps = mean_abs_rate(c, used, fitted);
  return all;
}

// Jackknife, floored by the model-based error (header comment).
void set_standard_errors(const Context& c, const std::vector<int>& used, const Solution& all,
                         const GyroFixesOptions& o, GyroFixesCheck& out) {
  GyroCheck& g = out.gyro;
  const std::array<std::vector<double>, 3> jk = jackknife(c, used, all, o);
  out.fits += static_cast<int>(used.size());
  const auto floored = [](double jk_se, double model_se) {
    return std::isfinite(jk_se) && std::isfinite(model_se) ? std::max(jk_se, model_se) : kNaN;
  };
  out.scale_jackknife_se = jackknife_se(jk[0]);
  out.bias_jackknife_se = jackknife_se(jk[1]);
  out.scale_model_se = all.model_se[0];
  out.bias_model_se = all.model_se[1];
  g.scale.std_error = floored(out.scale_jackknife_se, out.scale_model_se);
  g.bias.std_error = floored(out.bias_jackknife_se, out.bias_model_se);
  if (o.fit_distance_scale) out.distance_scale_std_error = floored(jackknife_se(jk[2]), all.model_se[2]);
}

// Held-out proof: train on the first windows, test on the last.
void heldout_proof(const Context& c, const std::vector<int>& used,
                   const std::vector<Pose<double>>& start_anchor, const GyroFixesOptions& o,
                   GyroFixesCheck& out) {
  const int n_used = static_cast<int>(used.size());
  const int n_held = std::clamp(static_cast<int>(std::lround(o.heldout_fraction * n_used)), 1, n_used - 2);
  out.train_windows.assign(used.begin(), used.end() - n_held);
  out.heldout_windows.assign(used.end() - n_held, used.end());
  const Solution train = solve(c, out.train_windows, start_for(used, start_anchor, out.train_windows), o);
  ++out.fits;
  out.train_scale = train.gyro[0];
  out.train_bias_radps = train.gyro[1];
  const GyroParams<double> tr{train.gyro[0], train.gyro[1], train.gyro[2]};
  out.joint = compare(c, out.heldout_windows, {1.0, 0.0, tr.q}, tr, "joint", o);
  out.scale_own = compare(c, out.heldout_windows, {1.0, tr.b, tr.q}, tr, "gyro_scale.s", o);
  out.bias_own = compare(c, out.heldout_windows, {tr.s, 0.0, tr.q}, tr, "gyro_bias.b", o);
}

// Verdicts: each parameter's z against its no-op, its held-out test, and its
// drift over relevance_window_s against the gyro noise's.
void judge_verdicts(const GyroFixesOptions& o, double dt_gyro, GyroFixesCheck& out) {
  GyroCheck& g = out.gyro;
  const double T = o.relevance_window_s;
  g.scale.drift = std::abs(g.scale.value - 1.0) * g.mean_abs_rate_radps * T;
  g.bias.drift = std::abs(g.bias.value) * T;
  g.scale.noise_drift = g.bias.noise_drift = g.noise_sigma_radps * std::sqrt(T * dt_gyro);
  const auto judge = [&](Verdict& v, const HeldoutComparison& own) {
    v.z = (v.value - v.noop) / v.std_error;
    v.significant = std::isfinite(v.z) && std::abs(v.z) > o.z_threshold && own.passed;
    v.relevant = std::isfinite(v.drift) && std::isfinite(v.noise_drift) &&
                 v.drift > std::max(o.relevance_factor * v.noise_drift, o.min_drift_rad);
  };
  judge(g.scale, out.scale_own);
  judge(g.bias, out.bias_own);
}

}  // namespace

bool GyroFixesOptions::IsValid(std::string* why) const {
  if (!check_option_rules(
          {
              {is_positive(window_s), "window_s", window_s, "> 0 [s]"},
              {is_positive(min_window_s), "min_window_s", min_window_s, "> 0 [s]"},
              {loss == RobustLoss::none || loss == RobustLoss::huber || loss == RobustLoss::cauchy, "loss",
               static_cast<double>(static_cast<int>(loss)), "none, huber or cauchy"},
              {is_positive(loss_scale), "loss_scale", loss_scale, "> 0 [fix sigmas]"},
              {max_iterations >= 1 && max_iterations <= 100000, "max_iterations",
               static_cast<double>(max_iterations), "in [1, 100000]"},
              {is_non_negative(min_spread_sigmas), "min_spread_sigmas", min_spread_sigmas, ">= 0"},
              {is_positive(min_standstill_s), "min_standstill_s", min_standstill_s, "> 0 [s]"},
              {is_non_negative(standstill_trim_s), "standstill_trim_s", standstill_trim_s, ">= 0 [s]"},
              {is_positive(heldout_fraction) && heldout_fraction < 1, "heldout_fraction", heldout_fraction,
               "in (0, 1)"},
              {is_positive(alpha) && alpha < 1, "alpha", alpha, "in (0, 1)"},
              {is_non_negative(min_informative), "min_informative", min_informative, ">= 0"},
              {is_positive(z_threshold), "z_threshold", z_threshold, "> 0"},
              {is_positive(relevance_window_s), "relevance_window_s", relevance_window_s, "> 0 [s]"},
              {is_non_negative(relevance_factor), "relevance_factor", relevance_factor, ">= 0"},
              {is_non_negative(min_drift_rad), "min_drift_rad", min_drift_rad, ">= 0 [rad]"},
          },
          why))
    return false;
  std::string w;
  if (!model.IsValid(&w)) {
    return core::invalid(why, "model: " + w);
  }
  return true;
}

GyroFixesCheck check_gyro_with_fixes(const DiagInput& in, const GyroFixesOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("gyro fixes check options: " + why);
  const GyroFixesOptions o = options_for_track(in, options);
  const auto t_start = std::chrono::steady_clock::now();
  GyroFixesCheck out;
  out.window_s = o.window_s;
  GyroCheck& g = out.gyro;
  g.scale.name = "gyro_scale.s";
  g.scale.noop = 1.0;
  g.bias.name = "gyro_bias.b";
  g.bias.noop = 0.0;
  const auto finish = [&](std::string reason) {
    g.unavailable_reason = std::move(reason);
    out.time_s = core::seconds_since(t_start);
    return out;
  };

  check_input(in);
  if (in.gyro_t_s.size() < 3) return finish("no gyro");
  if (in.odo_t_s.size() < 2) return finish("no odometry");
  if (in.ref_t_s.size() < kMinFixes) return finish("fewer than 3 reference positions");
  Context c;
  std::vector<bool> still_interval;
  if (std::string reason = prepare(in, o, c, still_interval); !reason.empty()) return finish(reason);
  out.num_windows = static_cast<int>(c.windows.size());
  std::vector<Pose<double>> start_anchor;
  const std::vector<int> used = select_windows(c, o, start_anchor, out.skipped_windows);
  out.used_windows = used;
  const int n_used = static_cast<int>(used.size());
  g.bins = n_used;
  if (n_used < kMinWindows)
    return finish(fmt::format("{} usable window(s) of {} s (expected at least {}: a held-out proof "
                              "needs training and held-out windows)",
                              n_used, o.window_s, kMinWindows));

  const double dt_gyro = gyro_noise_and_standstill(in, o, c, still_interval, used, out);
  const Solution all = fit_all_windows(c, used, start_anchor, o, out);
  set_standard_errors(c, used, all, o, out);
  heldout_proof(c, used, start_anchor, o, out);
  judge_verdicts(o, dt_gyro, out);
  out.time_s = core::seconds_since(t_start);
  return out;
}

}  // namespace odotune::diagnose

#include <odotune/diagnose/cross_validate.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <utility>

#include <Eigen/Dense>
#include <fmt/format.h>

#include <odotune/core/non_finite.h>
#include <odotune/core/robust_stats.h>
#include <odotune/diagnose/paired_test.h>

namespace odotune::diagnose {

namespace {
using core::kNaN;

// Local quadratic least-squares fit of (t, v) over [lo, hi) evaluated at tc,
// and its noise factor sqrt(e0' (X'X)^-1 e0) for white noise; the value at
// `self` and factor 1 with fewer than 5 samples.
std::pair<double, double> local_quadratic(const std::vector<double>& t, const std::vector<double>& v,
                                          std::size_t lo, std::size_t hi, std::size_t self) {
  if (hi - lo < 5) return {v[self], 1.0};
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (std::size_t j = lo; j < hi; ++j) {
    const double x = t[j] - t[self];
    const Eigen::Vector3d phi(1.0, x, x * x);
    a += phi * phi.transpose();
    b += phi * (v[j] - v[self]);
  }
  const Eigen::Matrix3d inv = a.inverse();
  const double c = (inv * b)(0);
  if (!std::isfinite(c) || !(inv(0, 0) > 0.0)) return {v[self], 1.0};
  return {v[self] + c, std::sqrt(inv(0, 0))};
}

}  // namespace

int denoised_reference(const DiagInput& in, double rate_hz, double half_s, double heading_half_s,
                       const ModelOptions& model, DiagInput& out, double& correlated) {
  correlated = 1.0;
  // A mixed reference (per-sample weights) is used as it is: a local fit
  // across samples of different noise would need the weights too, and mixes
  // are sparse (a known start plus fixes, fixes filling ground-truth gaps).
  if (!(rate_hz > 0.0) || in.ref_t_s.size() < 3 || !in.ref_w.empty()) return 1;
  const auto& t = in.ref_t_s;
  const double period = core::median_period_s(t, core::MedianRule::upper_middle);
  const int stride = static_cast<int>(std::floor(1.0 / period / rate_hz + 1e-9));
  if (stride <= 1) return 1;
  const bool heading = in.has_ref_heading();
  correlated = std::max(1.0, 2.0 * std::max(half_s, heading ? heading_half_s : 0.0) / (stride * period));
  // Heading residual against a trend that turns with the robot: the
  // integrated gyro (on time whatever the odometry does), else the nominal
  // odometry heading (S_r - S_l)/D. Linear interpolation at the reference times.
  std::vector<double> dth;
  if (heading) {
    std::vector<double> tt, th;
    if (in.gyro_t_s.size() >= 2) {
      tt = in.gyro_t_s;
      th.assign(tt.size(), 0.0);
      for (std::size_t i = 1; i < tt.size(); ++i)
        th[i] = th[i - 1] + 0.5 * (tt[i] - tt[i - 1]) * (in.gyro_z_radps[i] + in.gyro_z_radps[i - 1]);
    } else {
      const EffectModel nominal(in, EffectSet(), model);
      const OdoSeries& d = nominal.series();
      tt = d.t_s;
      for (std::size_t i = 0; i < tt.size(); ++i) th.push_back((d.s_r_m[i] - d.s_l_m[i]) / d.wheel_base_m);
    }
    std::size_t j = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      while (j + 2 < tt.size() && tt[j + 1] <= t[i]) ++j;
      const double f = std::clamp((t[i] - tt[j]) / (tt[j + 1] - tt[j]), 0.0, 1.0);
      dth.push_back(in.ref_theta_rad[i] - (th[j] + f * (th[j + 1] - th[j])));
    }
  }
  out = in;
  out.ref_t_s.clear();
  out.ref_x_m.clear();
  out.ref_y_m.clear();
  out.ref_theta_rad.clear();
  std::vector<double> fp, fh;
  std::size_t lo = 0, hi = 0, hlo = 0, hhi = 0;
  for (std::size_t k = 0; k < t.size(); k += static_cast<std::size_t>(stride)) {
    while (lo < t.size() && t[lo] < t[k] - half_s) ++lo;
    while (hi < t.size() && t[hi] <= t[k] + half_s) ++hi;
    const auto x = local_quadratic(t, in.ref_x_m, lo, hi, k);
    out.ref_t_s.push_back(t[k]);
    out.ref_x_m.push_back(x.first);
    out.ref_y_m.push_back(local_quadratic(t, in.ref_y_m, lo, hi, k).first);
    fp.push_back(x.second);
    if (!heading) continue;
    while (hlo < t.size() && t[hlo] < t[k] - heading_half_s) ++hlo;
    while (hhi < t.size() && t[hhi] <= t[k] + heading_half_s) ++hhi;
    const auto h = local_quadratic(t, dth, hlo, hhi, k);
    out.ref_theta_rad.push_back(in.ref_theta_rad[k] - dth[k] + h.first);
    fh.push_back(h.second);
  }
  out.ref_sigma_m = std::max(in.ref_sigma_m * core::median(std::move(fp), core::MedianRule::upper_middle),
                             1e-3);
  if (heading)
    out.ref_sigma_rad = std::max(in.ref_sigma_rad * core::median(std::move(fh), core::MedianRule::upper_middle),
                                 1e-3);
  return stride;
}

EffectSet start_from(const EffectSet& structure, const EffectSet& warm) {
  std::vector<double> v = pack(structure);
  const auto layout = param_layout(structure);
  for (std::size_t j = 0; j < layout.size(); ++j)
    if (layout[j].fitted && warm.on(layout[j].effect))
      v[j] = warm.params(layout[j].effect)[static_cast<std::size_t>(layout[j].index)];
  return unpack(structure, v);
}

namespace {

// Per window, the recording it is anchored in (the last start at or before
// its anchor time), renumbered over the recordings that have windows; empty
// when fewer than two recordings have windows.
std::vector<int> recording_folds(const std::vector<Window>& windows, const std::vector<double>& starts_s) {
  if (starts_s.size() < 2) return {};
  std::vector<int> raw;
  for (const Window& w : windows) {
    const auto it = std::upper_bound(starts_s.begin(), starts_s.end(), w.t_begin_s);
    raw.push_back(std::max(0, static_cast<int>(it - starts_s.begin()) - 1));
  }
  std::vector<int> used(raw);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  if (used.size() < 2) return {};
  for (int& f : raw) f = static_cast<int>(std::lower_bound(used.begin(), used.end(), f) - used.begin());
  return raw;
}

}  // namespace

CrossValidator::CrossValidator(const DiagInput& in, const FitOptions& fit, int folds, double correlated_samples,
                               const std::vector<double>& recording_starts_s)
    : in_(&in), fit_(fit), corr_(correlated_samples) {
  if (!(corr_ >= 1.0 && std::isfinite(corr_)))
    throw std::invalid_argument(fmt::format("correlated_samples = {}; expected >= 1", correlated_samples));
  std::string why;
  if (!fit.IsValid(&why)) throw std::invalid_argument("fit options: " + why);
  if (folds < 2) throw std::invalid_argument(fmt::format("folds = {}; expected >= 2", folds));
  windows_ = make_windows(in, fit.window_s);
  const int n = static_cast<int>(windows_.size());
  const std::vector<int> by_recording = recording_folds(windows_, recording_starts_s);
  by_recording_ = !by_recording.empty();
  const int k = by_recording_ ? *std::max_element(by_recording.begin(), by_recording.end()) + 1
                              : std::min(folds, n);
  train_.resize(static_cast<std::size_t>(k));
  test_.resize(static_cast<std::size_t>(k));
  for (int w = 0; w < n; ++w) {
    const int f = by_recording_ ? by_recording[static_cast<std::size_t>(w)]
                                : static_cast<int>(static_cast<long>(w) * k / n);
    for (int g = 0; g < k; ++g) (g == f ? test_ : train_)[static_cast<std::size_t>(g)].push_back(w);
  }
  heading_ = in.has_ref_heading() && fit.use_heading;
  comps_ = heading_ ? 3 : 2;
  ism_ = 1.0 / in.ref_sigma_m;
  ish_ = heading_ ? 1.0 / in.ref_sigma_rad : 0.0;
  for (const Window& w : windows_) n_samples_ += w.ref_end - w.ref_begin;
}

namespace {

// The effects of `set` other than `trial`.
std::vector<Effect> others(const EffectSet& set, Effect trial) {
  std::vector<Effect> out;
  for (int e = 0; e < kNumEffects; ++e)
    if (static_cast<Effect>(e) != trial && set.on(static_cast<Effect>(e)))
      out.push_back(static_cast<Effect>(e));
  return out;
}

}  // namespace

FitSummary CrossValidator::screen(const EffectSet& start, Effect trial, const std::vector<int>& windows,
                                  int max_iterations) {
  FitOptions o = fit_;
  o.max_iterations = max_iterations;
  o.standard_errors = false;
  o.held_effects = others(start, trial);
  ++fits_;
  return fit_effects(model_for(start), *in_, start, windows, {}, o);
}

std::vector<double> CrossValidator::settled_costs(const EffectSet& at, Effect trial) {
  FitOptions o = fit_;
  o.max_iterations = 1;  // the settled costs are read before the fit moves anything
  o.standard_errors = false;
  o.settle_anchors = true;
  o.held_effects = others(at, trial);
  ++fits_;
  const FitSummary f = fit_effects(model_for(at), *in_, at, {}, {}, o);
  std::vector<double> out(windows_.size(), 0.0);
  for (std::size_t i = 0; i < f.fitted_windows.size() && i < f.settled_window_costs.size(); ++i)
    out[static_cast<std::size_t>(f.fitted_windows[i])] = f.settled_window_costs[i];
  return out;
}

FitSummary CrossValidator::fit(const EffectSet& start, const std::vector<int>& train, int max_iterations) {
  FitOptions o = fit_;
  o.max_iterations = max_iterations;
  o.standard_errors = false;  // the search reads costs and values only
  ++fits_;
  return fit_effects(model_for(start), *in_, start, train, {}, o);
}

const EffectModel& CrossValidator::model_for(const EffectSet& set) {
  std::string key;
  for (int e = 0; e < kNumEffects; ++e) key += set.on(static_cast<Effect>(e)) ? '1' : '0';
  {
    const std::lock_guard<std::mutex> lock(models_mutex_);
    const auto it = models_.find(key);
    if (it != models_.end()) return *it->second;
  }
  // Built outside the lock (other threads keep fitting); two threads that
  // build the same model keep the first, which equals the second.
  auto built = std::make_unique<EffectModel>(*in_, set, fit_.model);
  const std::lock_guard<std::mutex> lock(models_mutex_);
  auto& model = models_[key];
  if (!model) model = std::move(built);
  return *model;
}

SamplePred CrossValidator::empty_pred() const {
  const std::size_t n = in_->ref_t_s.size();
  return {std::vector<double>(n, kNaN), std::vector<double>(n, kNaN), std::vector<double>(n, kNaN)};
}

void CrossValidator::predict(const EffectSet& set, const std::vector<int>& which, SamplePred& p) {
  const ReplayResult r = replay(model_for(set), pack(set), *in_, windows_, which, nullptr,
                                fit_anchoring(*in_, fit_));
  for (int wi : which) {
    const Window& w = windows_[static_cast<std::size_t>(wi)];
    for (std::size_t g = w.ref_begin; g < w.ref_end; ++g) {
      p.x_m[g] = r.pred_x_m[g];
      p.y_m[g] = r.pred_y_m[g];
      p.theta_rad[g] = r.pred_theta_rad[g];
    }
  }
}

void CrossValidator::finish(SetEval& e) const {
  const DiagInput& in = *in_;
  e.window_sse.assign(windows_.size(), 0.0);
  double sp = 0.0, sh = 0.0, all = 0.0;
  for (std::size_t w = 0; w < windows_.size(); ++w)
    for (std::size_t g = windows_[w].ref_begin; g < windows_[w].ref_end; ++g) {
      const double dx = e.pred.x_m[g] - in.ref_x_m[g], dy = e.pred.y_m[g] - in.ref_y_m[g];
      const double dh = heading_ ? e.pred.theta_rad[g] - in.ref_theta_rad[g] : 0.0;
      e.window_sse[w] += (dx * dx + dy * dy) * ism_ * ism_ * in.ref_weight(g) + dh * dh * ish_ * ish_;
      sp += dx * dx + dy * dy;
      sh += dh * dh;
    }
  for (double s : e.window_sse) all += s;
  const auto n = static_cast<double>(n_samples_);
  e.score = all / n;
  e.pos_rmse_m = std::sqrt(sp / n);
  e.heading_rmse_rad = heading_ ? std::sqrt(sh / n) : kNaN;
  e.ok = std::isfinite(e.score);
  if (!e.ok) e.error = "non-finite prediction";
}

SetEval CrossValidator::cross_validate(const EffectSet& structure, const std::vector<EffectSet>& warm,
                                       int max_iterations) {
  return std::move(cross_validate_all({structure}, warm, max_iterations).front());
}

std::vector<SetEval> CrossValidator::cross_validate_all(
    const std::vector<EffectSet>& structures, const std::vector<EffectSet>& warm, int max_iterations) {
  const std::size_t n_sets = structures.size(), k = test_.size();
  std::vector<SetEval> out(n_sets);
  for (SetEval& e : out) {
    e.pred = empty_pred();
    e.folds.resize(k);
  }
  // One task per (set, fold): fit on the other folds, predict the fold's own
  // windows (disjoint samples of the set's pred). Errors are kept per task
  // and the first fold's reported, as a serial loop would.
  std::vector<std::string> errors(n_sets * k);
  const auto tasks = static_cast<long>(n_sets * k);
#pragma omp parallel for schedule(dynamic, 1) if (tasks > 1)
  for (long t = 0; t < tasks; ++t) {
    const auto s = static_cast<std::size_t>(t) / k, f = static_cast<std::size_t>(t) % k;
    const EffectSet& structure = structures[s];
    SetEval& e = out[s];
    try {
      if (structure.empty()) {
        e.folds[f] = structure;
      } else {
        const EffectSet start = warm.size() == k ? start_from(structure, warm[f]) : structure;
        e.folds[f] = fit(start, train_[f], max_iterations).effects;
      }
      predict(e.folds[f], test_[f], e.pred);
    } catch (const std::exception& ex) {
      errors[static_cast<std::size_t>(t)] = ex.what();
      if (errors[static_cast<std::size_t>(t)].empty()) errors[static_cast<std::size_t>(t)] = "fit failed";
    }
  }
  for (std::size_t s = 0; s < n_sets; ++s) {
    for (std::size_t f = 0; f < k && out[s].error.empty(); ++f) out[s].error = errors[s * k + f];
    if (out[s].error.empty()) finish(out[s]);
  }
  return out;
}

SetEval CrossValidator::fit_all(const EffectSet& structure, const EffectSet& warm, int max_iterations) {
  SetEval e;
  e.pred = empty_pred();
  e.cost = kNaN;
  std::vector<int> all(windows_.size());
  for (std::size_t w = 0; w < all.size(); ++w) all[w] = static_cast<int>(w);
  try {
    e.fitted = structure;
    if (!structure.empty()) {
      const FitSummary s = fit(start_from(structure, warm), {}, max_iterations);
      e.fitted = s.effects;
      e.cost = s.final_cost;
    }
    predict(e.fitted, all, e.pred);
  } catch (const std::exception& ex) {
    e.error = ex.what();
    return e;
  }
  finish(e);
  int p = (structure.on(Effect::radius_step) ? 1 : 0) + (structure.on(Effect::slip_zone) ? 4 : 0) +
          (fit_anchoring(*in_, fit_) == Anchoring::free ? 3 * static_cast<int>(all.size()) : 0);
  for (const ParamSlot& s : param_layout(structure)) p += s.fitted ? 1 : 0;
  const auto n = static_cast<double>(n_samples_);
  e.bic = n * std::log(std::max(e.score, 1e-300)) + static_cast<double>(p) * std::log(n);
  return e;
}

SetEval CrossValidator::own_noop(const SetEval& cv, Effect e) {
  SetEval out;
  out.pred = empty_pred();
  try {
    for (std::size_t f = 0; f < test_.size() && f < cv.folds.size(); ++f) {
      std::vector<double> v = pack(cv.folds[f]);
      const auto layout = param_layout(cv.folds[f]);
      for (std::size_t j = 0; j < layout.size(); ++j)
        if (layout[j].effect == e && layout[j].fitted) v[j] = layout[j].noop;
      out.folds.push_back(unpack(cv.folds[f], v));
      predict(out.folds.back(), test_[f], out.pred);
    }
  } catch (const std::exception& ex) {
    out.error = ex.what();
    return out;
  }
  finish(out);
  return out;
}

CrossValidator::Replayed CrossValidator::replayed(const SetEval& cv) {
  PooledError p;
  for (std::size_t f = 0; f < test_.size(); ++f) {
    const EffectSet set = f < cv.folds.size() ? cv.folds[f] : EffectSet{};
    p.add(replay(model_for(set), pack(set), *in_, windows_, test_[f]));
  }
  Replayed out;
  if (!p.empty()) {
    out.pos_rmse_m = p.pos_rmse_m();
    out.heading_rmse_rad = p.heading_rmse_rad();
  }
  return out;
}

PairedComparison CrossValidator::compare(const SetEval& ref, const SetEval& alt, double alpha) const {
  std::vector<WindowPair> pairs;
  for (std::size_t w = 0; w < windows_.size(); ++w) {
    const Window& win = windows_[w];
    const double delta2 = normalised_sq_distance(*in_, win, {alt.pred.x_m, alt.pred.y_m, alt.pred.theta_rad},
                                                 {ref.pred.x_m, ref.pred.y_m, ref.pred.theta_rad}, heading_);
    const auto n = static_cast<double>(win.ref_end - win.ref_begin);
    pairs.push_back({ref.window_sse[w], alt.window_sse[w], delta2, n * comps_});
  }
  PairedComparison out = paired_windows(pairs, corr_, alpha);
  out.gain = ref.score - alt.score;
  out.rel = out.gain / ref.score;
  return out;
}

}  // namespace odotune::diagnose

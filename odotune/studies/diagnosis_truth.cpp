#include <odotune/studies/diagnosis_truth.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <odotune/core/non_finite.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/gyro_heading_input.h>
#include <odotune/diagnose/recordings.h>
#include <odotune/diagnose/select.h>
#include <odotune/diagnose/series_interp.h>
#include <odotune/diagnose/window_replay.h>
#include <odotune/sim/effects.h>

namespace odotune::studies {

namespace {

using core::kNaN;

using diagnose::DiagInput;
using diagnose::Effect;
using diagnose::EffectSet;

bool is_noop(const TrueEffect& e) {
  const sim::EffectInfo* info = sim::find_effect(e.name());
  for (const auto& [name, v] : e.params) {
    const sim::EffectParamInfo* p = info ? sim::find_param(*info, name) : nullptr;
    // radius_step.t and the slip_zone box have no no-op value of their own.
    const bool position = (e.effect == Effect::radius_step && name == "t") ||
                          (e.effect == Effect::slip_zone &&
                           (name == "x0" || name == "x1" || name == "y0" || name == "y1"));
    if (p && !position && v != p->default_value) return false;
  }
  return true;
}

// Position and heading RMSE pooled over the windows `which` of an
// all-window replay (each window is anchored on its own, so this is what a
// replay of those windows alone gives, without replaying them again).
struct Pooled {
  double pos_m = kNaN, heading_rad = kNaN;
};
Pooled pooled(const diagnose::PooledError& p) {
  return p.empty() ? Pooled{} : Pooled{p.pos_rmse_m(), p.heading_rmse_rad()};
}
Pooled pooled(const diagnose::ReplayResult& r, const std::vector<int>& which) {
  diagnose::PooledError p;
  for (const diagnose::WindowError& w : r.windows)
    if (std::find(which.begin(), which.end(), w.window) != which.end()) p.add(w);
  return pooled(p);
}

// The true wheel effects, but `without` (none when unset).
EffectSet wheel_set(const std::vector<TrueEffect>& truth, std::optional<Effect> without = std::nullopt) {
  EffectSet set;
  for (const TrueEffect& e : truth) {
    if (diagnose::is_gyro_effect(e.effect) || e.effect == without) continue;
    set.enable(e.effect);
    for (const auto& [name, v] : e.params) set.set(e.effect, name, v);
  }
  return set;
}

// Held out: the last windows holding >= heldout_fraction of the scored
// reference samples (header comment); none with fewer than 2 windows.
std::vector<int> heldout_tail(const diagnose::ReplayResult& all, double heldout_fraction) {
  const auto n = static_cast<int>(all.windows.size());
  std::size_t total = 0, tail = 0;
  for (const diagnose::WindowError& w : all.windows) total += w.n_ref;
  std::vector<int> held;
  for (int i = n - 1; i >= 0 && static_cast<double>(tail) < heldout_fraction * static_cast<double>(total);
       --i) {
    held.insert(held.begin(), all.windows[static_cast<std::size_t>(i)].window);
    tail += all.windows[static_cast<std::size_t>(i)].n_ref;
  }
  if (n < 2) held.clear();  // nothing to train on: no split
  return held;
}

// The materiality rule's heading part (select.h).
bool heading_material(double gain_rad, double floor_rad) {
  return std::isfinite(gain_rad) && std::isfinite(floor_rad) && gain_rad > 0.0 && gain_rad >= floor_rad;
}

// What judging each true effect on one track needs: the scoring input, the
// nominal all-window replay, the held-out windows, and the true model's
// heading error and the heading floor (with a reference heading).
struct TrackJudge {
  const DiagInput& in;
  const DiagInput& scoring;
  const std::vector<TrueEffect>& truth;
  const diagnose::ReplayResult& all;
  const std::vector<int>& held;
  double window_s;
  const diagnose::MaterialityOptions& materiality;
  bool heading = false;
  double true_heading_rad = kNaN, heading_floor_rad = kNaN;

  double heldout_rmse(const DiagInput& input, const EffectSet& set) const {
    return diagnose::replay(input, set, window_s, held).pos_rmse_m;
  }
};

// Gyro effects: the true corrections, each left out in turn, on the
// gyro-heading replay (lateral_skid acts on it too).
struct GyroTruth {
  bool gyro = false;  // the track has a gyro
  double bias = 0.0, scale = 1.0;
  EffectSet body;
  double floor_m = 0.0, after_m = 0.0;
};
GyroTruth gyro_truth(const TrackJudge& j) {
  GyroTruth g;
  g.gyro = !j.in.gyro_t_s.empty();
  for (const TrueEffect& e : j.truth) {
    if (e.effect == Effect::gyro_bias) g.bias = e.param("b");
    if (e.effect == Effect::gyro_scale) g.scale = e.param("s");
  }
  for (const TrueEffect& e : j.truth)
    if (e.effect == Effect::lateral_skid)
      g.body.enable(Effect::lateral_skid).set(Effect::lateral_skid, "k", e.param("k"));
  const bool any_gyro = std::any_of(j.truth.begin(), j.truth.end(),
                                    [](const TrueEffect& e) { return diagnose::is_gyro_effect(e.effect); });
  if (g.gyro && any_gyro) {
    g.floor_m = diagnose::materiality_floor_m(
        j.in.ref_sigma_m, j.heldout_rmse(diagnose::gyro_heading_input(j.scoring, 0.0, 1.0), g.body),
        j.materiality);
    g.after_m = j.heldout_rmse(diagnose::gyro_heading_input(j.scoring, g.bias, g.scale), g.body);
  }
  return g;
}

// A slip_zone or radius_step is bound to a place or a time: judged on every
// window but the one where it gains most (header comment: one window cannot
// both fit it and prove it), whether or not the held-out tail shows it.
void judge_on_all_windows(const TrackJudge& j, EffectTruth& t) {
  const diagnose::ReplayResult wo = diagnose::replay(j.scoring, wheel_set(j.truth, t.effect.effect),
                                                     j.window_s);
  const diagnose::ReplayResult wi = diagnose::replay(j.scoring, wheel_set(j.truth), j.window_s);
  std::vector<int> rest;
  std::size_t top = 0;
  double top_gain = -1.0;
  for (std::size_t k = 0; k < wo.windows.size(); ++k) {
    const double g = wo.windows[k].pos_rmse_m * wo.windows[k].pos_rmse_m -
                     wi.windows[k].pos_rmse_m * wi.windows[k].pos_rmse_m;
    const double gain = g * static_cast<double>(wo.windows[k].n_ref);
    if (gain > top_gain) {
      top_gain = gain;
      top = k;
    }
  }
  for (std::size_t k = 0; k < wo.windows.size(); ++k)
    if (k != top) rest.push_back(wo.windows[k].window);
  bool rest_material = false;
  double before = kNaN, after = kNaN, floor = kNaN;
  if (!rest.empty()) {
    const Pooled b = pooled(wo, rest), a = pooled(wi, rest), n0 = pooled(j.all, rest);
    before = b.pos_m;
    after = a.pos_m;
    floor = diagnose::materiality_floor_m(j.in.ref_sigma_m, n0.pos_m, j.materiality);
    rest_material = diagnose::is_material(before, after, floor) ||
                    (j.heading && heading_material(diagnose::removed_error_m(b.heading_rad, a.heading_rad),
                                                   diagnose::materiality_floor_m(
                                                       j.in.ref_sigma_rad, n0.heading_rad, j.materiality)));
  }
  if (!rest_material) {
    t.detectable = false;  // seen in one window at most
  } else if (!t.detectable) {
    t.detectable = true;
    t.on_all_windows = true;
    t.before_m = before;
    t.after_m = after;
    t.gain_m = diagnose::removed_error_m(before, after);
    t.floor_m = floor;
  }
}

// One true effect's held-out gain against its floor, and whether it is detectable.
void judge_effect(const TrackJudge& j, const GyroTruth& g, const Detectability& out, EffectTruth& t) {
  if (t.gyro) {
    if (!g.gyro) return;
    const bool b = t.effect.effect == Effect::gyro_bias;
    t.before_m = j.heldout_rmse(diagnose::gyro_heading_input(j.scoring, b ? 0.0 : g.bias, b ? g.scale : 1.0),
                                g.body);
    t.after_m = g.after_m;
    t.floor_m = g.floor_m;
  } else {
    const diagnose::ReplayResult without = diagnose::replay(j.scoring, wheel_set(j.truth, t.effect.effect),
                                                            j.window_s, j.held);
    t.before_m = without.pos_rmse_m;
    t.after_m = out.true_heldout_m;
    t.floor_m = out.floor_m;
    if (j.heading) {  // the materiality rule's heading part (select.h)
      t.heading_gain_rad = diagnose::removed_error_m(without.heading_rmse_rad, j.true_heading_rad);
      t.heading_floor_rad = j.heading_floor_rad;
    }
  }
  t.gain_m = diagnose::removed_error_m(t.before_m, t.after_m);
  t.detectable = !is_noop(t.effect) && (diagnose::is_material(t.before_m, t.after_m, t.floor_m) ||
                                        heading_material(t.heading_gain_rad, t.heading_floor_rad));
  if (!is_noop(t.effect) && (t.effect.effect == Effect::slip_zone || t.effect.effect == Effect::radius_step))
    judge_on_all_windows(j, t);
}

}  // namespace

int Detectability::detectable_count() const {
  return static_cast<int>(std::count_if(effects.begin(), effects.end(),
                                        [](const EffectTruth& e) { return e.detectable; }));
}

Detectability assess_detectability(const DiagInput& in, const std::vector<TrueEffect>& truth,
                                   const diagnose::MaterialityOptions& materiality) {
  const diagnose::SelectOptions so;
  Detectability out;
  out.ref_sigma_m = in.ref_sigma_m;
  out.window_s = diagnose::selection_window_s(in, so);
  const diagnose::SelectionInput si = diagnose::selection_input(in, so);
  const DiagInput& scoring = si.stride > 1 ? si.input : in;
  const diagnose::ReplayResult all = diagnose::replay(scoring, EffectSet{}, out.window_s);
  const std::vector<int> held = heldout_tail(all, so.heldout_fraction);
  out.windows = static_cast<int>(all.windows.size());
  out.heldout_windows = static_cast<int>(held.size());
  for (const TrueEffect& e : truth) {
    EffectTruth t;
    t.effect = e;
    t.gyro = diagnose::is_gyro_effect(e.effect);
    out.effects.push_back(t);
  }
  if (held.empty()) return out;
  TrackJudge j{in, scoring, truth, all, held, out.window_s, materiality};

  // Wheel-odometry effects.
  out.nominal_heldout_m = j.heldout_rmse(scoring, EffectSet{});
  out.true_heldout_m = j.heldout_rmse(scoring, wheel_set(truth));
  out.floor_m = diagnose::materiality_floor_m(in.ref_sigma_m, out.nominal_heldout_m, materiality);
  // With a reference heading, the materiality rule also accepts a material heading gain.
  j.heading = in.has_ref_heading();
  if (j.heading) {
    j.true_heading_rad = diagnose::replay(scoring, wheel_set(truth), out.window_s, held).heading_rmse_rad;
    j.heading_floor_rad = diagnose::materiality_floor_m(
        in.ref_sigma_rad, diagnose::replay(scoring, EffectSet{}, out.window_s, held).heading_rmse_rad,
        materiality);
  }
  const GyroTruth g = gyro_truth(j);
  for (EffectTruth& t : out.effects) judge_effect(j, g, out, t);
  return out;
}

Detectability assess_recordings_detectability(const std::vector<DiagInput>& fit,
                                              const std::vector<DiagInput>& heldout,
                                              const std::vector<TrueEffect>& truth,
                                              const diagnose::MaterialityOptions& materiality) {
  if (fit.empty() || heldout.empty())
    throw std::invalid_argument("assess_recordings_detectability: needs fit and held-out recordings");
  const DiagInput pooled_fit = diagnose::pool_recordings(fit);
  // Gyro effects: on the fit recordings, as for one track.
  Detectability out = assess_detectability(pooled_fit, truth, materiality);
  out.window_s = diagnose::selection_window_s(pooled_fit, diagnose::SelectOptions{});
  const auto replay_all = [&](const EffectSet& set) {
    diagnose::PooledError p;
    for (const DiagInput& in : heldout) p.add(diagnose::replay(in, set, out.window_s));
    return pooled(p);
  };
  // The nominal replay, and the reference sigmas pooled as RMS over the
  // held-out recordings' scored samples.
  diagnose::PooledError nominal_sums, sigmas;
  out.windows = 0;
  for (const DiagInput& in : heldout) {
    const diagnose::ReplayResult r = diagnose::replay(in, EffectSet{}, out.window_s);
    nominal_sums.add(r);
    out.windows += static_cast<int>(r.windows.size());
    for (const diagnose::WindowError& w : r.windows) sigmas.add(in.ref_sigma_m, in.ref_sigma_rad, w.n_ref);
  }
  out.heldout_windows = out.windows;
  out.ref_sigma_m = sigmas.empty() ? heldout.front().ref_sigma_m : sigmas.pos_rmse_m();
  const Pooled nominal = pooled(nominal_sums), all_true = replay_all(wheel_set(truth));
  out.nominal_heldout_m = nominal.pos_m;
  out.true_heldout_m = all_true.pos_m;
  out.floor_m = diagnose::materiality_floor_m(out.ref_sigma_m, nominal.pos_m, materiality);
  const bool heading = heldout.front().has_ref_heading();
  const double sigma_rad = sigmas.heading_rmse_rad();
  const double heading_floor_rad =
      heading ? diagnose::materiality_floor_m(sigma_rad, nominal.heading_rad, materiality) : kNaN;
  for (EffectTruth& t : out.effects) {
    if (t.gyro) continue;
    const Pooled without = replay_all(wheel_set(truth, t.effect.effect));
    t.on_all_windows = false;
    t.before_m = without.pos_m;
    t.after_m = all_true.pos_m;
    t.floor_m = out.floor_m;
    t.gain_m = diagnose::removed_error_m(t.before_m, t.after_m);
    t.heading_gain_rad = heading ? diagnose::removed_error_m(without.heading_rad, all_true.heading_rad) : kNaN;
    t.heading_floor_rad = heading_floor_rad;
    const bool heading_material = std::isfinite(t.heading_gain_rad) && t.heading_gain_rad > 0.0 &&
                                  t.heading_gain_rad >= t.heading_floor_rad;
    t.detectable = !is_noop(t.effect) &&
                   (diagnose::is_material(t.before_m, t.after_m, t.floor_m) || heading_material);
  }
  return out;
}

}  // namespace odotune::studies

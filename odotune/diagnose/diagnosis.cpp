#include <odotune/diagnose/diagnosis.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/diagnose/gyro_heading_input.h>
#include <odotune/diagnose/materiality.h>
#include <odotune/diagnose/option_rules.h>
#include <odotune/diagnose/reconcile.h>
#include <odotune/diagnose/residual_series.h>
#include <odotune/diagnose/series_interp.h>
#include <odotune/diagnose/window_replay.h>

namespace odotune::diagnose {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The effect's physical description, used as `conditions` when the residuals
// do not single out a condition (the effect acts everywhere, a little).
std::string description(Effect e) {
  switch (e) {
    case Effect::radius_error: return "everywhere the wheels roll: travel off by a constant ratio per wheel";
    case Effect::wheel_base_error: return "whenever the robot turns: heading change off by a constant ratio";
    case Effect::radius_step: return "after the step time: a wheel's effective radius changed";
    case Effect::speed_radius: return "growing with wheel speed: faster wheels travel further per turn";
    case Effect::lateral_skid: return "in turns taken at speed: the body slides outward, growing with |v*w|";
    case Effect::longitudinal_slip: return "while accelerating or braking: the wheels slip";
    case Effect::slip_zone: return "inside one region of the floor: the wheels slip there";
    case Effect::gyro_bias: return "at all times, also at rest: the gyro's heading drifts at a constant rate";
    case Effect::gyro_scale: return "while turning: the gyro's heading error grows with the turn rate";
    case Effect::actuator_lag: return "when the commands change: the body follows them late";
    case Effect::time_offset: return "when the velocities change: the odometry's time stamps are shifted";
    case Effect::odometry_bias:
      return "at all times, also at rest: the odometry reads its body velocities with a constant offset";
  }
  return "";
}

double sq(double v) { return v * v; }

// Pooled position RMSE of the windows `which`, from a replay of all windows
// (windows replay independently, so this equals replaying only `which`);
// NaN for no window.
double pooled_pos_rmse(const ReplayResult& r, const std::vector<int>& which) {
  PooledError p;
  for (const WindowError& w : r.windows)
    if (std::find(which.begin(), which.end(), w.window) != which.end()) p.add(w);
  return p.pos_rmse_m();
}

BeforeAfter scores(const ReplayResult& before, const ReplayResult& after, const std::vector<int>& which) {
  if (which.empty()) return {};
  return {pooled_pos_rmse(before, which), pooled_pos_rmse(after, which)};
}

// Segments = maximal runs of consecutive windows (in time) whose position
// RMSE the effect reduces by at least half the largest reduction.
std::vector<TimeSegment> helped_windows(const ReplayResult& without, const ReplayResult& with) {
  std::vector<double> gain(with.windows.size());
  double best = 0.0;
  for (std::size_t i = 0; i < gain.size(); ++i) {
    gain[i] = without.windows[i].pos_rmse_m - with.windows[i].pos_rmse_m;
    best = std::max(best, gain[i]);
  }
  std::vector<TimeSegment> out;
  if (best <= 0.0) return out;
  for (std::size_t i = 0; i < gain.size(); ++i) {
    if (gain[i] < 0.5 * best) continue;
    const WindowError& w = with.windows[i];
    if (!out.empty() && i > 0 && gain[i - 1] >= 0.5 * best) {
      out.back().t1_s = w.t_end_s;
    } else {
      out.push_back({w.t_begin_s, w.t_end_s, 0.0, 0});
    }
  }
  return out;
}

std::string param_short_name(const std::string& slot_name) { return slot_name.substr(slot_name.find('.') + 1); }

// Share of the series' squared position error inside the segments, and the
// RMSE there.
struct Inside {
  double share = 0.0, rmse_m = 0.0;
};
Inside inside_segments(const ResidualSeries& s, const std::vector<TimeSegment>& segs) {
  double in_seg = 0.0, all = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < s.t_s.size(); ++i) {
    const double e = sq(s.ex_m[i]) + sq(s.ey_m[i]);
    all += e;
    for (const TimeSegment& g : segs)
      if (s.t_s[i] >= g.t0_s && s.t_s[i] <= g.t1_s) {
        in_seg += e;
        ++n;
        break;
      }
  }
  return {all > 0.0 ? in_seg / all : 0.0, n > 0 ? std::sqrt(in_seg / static_cast<double>(n)) : 0.0};
}

// Physics outside the list (term_search.h): terms that reproduce what the
// chosen model leaves, on the scoring input's windows and split. A model that
// passes the materiality floor goes on the `unexplained` finding: the
// located one (`located`, from locate.h) or, when nothing was located, one
// made here. Located growth that no term reproduces on the held-out windows
// is not a finding: it goes to `not_reproduced` (diagnosis.h).
void attach_term_model(Diagnosis& d, const DiagInput& in, const DiagInput& scoring, const EffectSet& wheel,
                       const DiagnoseOptions& o, std::optional<Finding>& located) {
  if (o.terms.enabled && !d.train_windows.empty()) {
    try {
      d.term_search = search_terms(scoring, wheel, make_windows(scoring, d.window_s), d.train_windows,
                                   d.heldout_windows, d.floor_m, o.terms);
    } catch (const std::invalid_argument& e) {  // an input the search cannot use: no model, the reason logged
      d.term_search.reason = std::string("term search not run: ") + e.what();
    }
  }
  if (!d.term_search.found) {
    if (located)
      d.not_reproduced.push_back(fmt::format(
          "unexplained: the chosen model's residuals grow faster than noise ({}), but no term "
          "reproduces that on held-out windows: random wheel slip or sensor noise, nothing to model",
          located->conditions.empty() ? "in places" : located->conditions));
    return;
  }
  const TermModel& tm = d.term_search.model;
  if (!located) {
    Finding f;
    f.kind = Unexplained{};
    f.segments.push_back({in.ref_t_s.front(), in.ref_t_s.back(), 0.0, 0});
    f.train = {tm.train.before_pos_rmse_m, tm.train.after_pos_rmse_m};
    f.heldout = {tm.heldout.before_pos_rmse_m, tm.heldout.after_pos_rmse_m};
    // Share of the nominal model's training error the terms remove.
    const double nominal = d.train.before_pos_rmse_m;
    f.explains = nominal > 0.0
                     ? std::max(0.0,
                                (sq(tm.train.before_pos_rmse_m) - sq(tm.train.after_pos_rmse_m)) / sq(nominal))
                     : 0.0;
    located = std::move(f);
  }
  Finding& f = *located;
  f.conditions = (f.conditions.empty() ? "" : f.conditions + "; ") + tm.conditions;
  f.evidence = (f.evidence.empty() ? "" : f.evidence + "; ") +
               fmt::format("a sparse regression over {} candidate terms, chosen by cross-validation, "
                           "lowers the held-out position error from {:.4f} m to {:.4f} m",
                           d.term_search.library_size, tm.heldout.before_pos_rmse_m,
                           tm.heldout.after_pos_rmse_m);
  f.model = tm;
  d.findings.push_back(std::move(f));
}

// What the findings are replayed on: the input, the scoring input (the
// selection's denoised reference, or `in` itself), the windows and their
// length.
struct ReplayContext {
  const DiagInput& in;
  const DiagInput& scoring;
  const std::vector<Window>& windows;
  double ws;
};

// The diagnosis of an input with too few reference samples to score any
// window: no finding, said plainly.
void mark_too_few_samples(Diagnosis& d, const DiagInput& in) {
  const double nan = std::nan("");
  d.baseline_pos_rmse_m = d.baseline_heading_rmse_rad = d.final_pos_rmse_m = d.final_heading_rmse_rad = nan;
  d.note = fmt::format("{} reference sample(s) ({} ground truth, {} fixes): too few to compare a model against "
                       "(a window needs {}); no finding",
                       in.ref_t_s.size(), in.ref_gt_samples, in.ref_fix_samples,
                       in.has_ref_heading() ? "2 poses" : "3 positions");
}

// Train / held-out split: the selection's, else its rule (last 30 %).
void set_train_heldout_split(Diagnosis& d, const Selection& sel, const std::vector<Window>& windows,
                             const DiagnoseOptions& o) {
  d.train_windows = sel.train_windows, d.heldout_windows = sel.heldout_windows;
  if (!sel.fitted) {
    d.train_windows.clear(), d.heldout_windows.clear();
    const auto n = static_cast<int>(windows.size());
    const int n_train = n - static_cast<int>(std::round(o.select.heldout_fraction * n));
    for (int i = 0; i < n; ++i) (i < n_train ? d.train_windows : d.heldout_windows).push_back(i);
  }
}

// The parameters of the selected effect `se` in the chosen model `wheel`, with
// their standard errors (a discrete parameter's: a quarter of its zone cell, or
// the step search's fine step).
void add_wheel_params(Finding& f, const SelectedEffect& se, const EffectSet& wheel,
                      const std::vector<ParamSlot>& layout, const Selection& sel, const DiagnoseOptions& o) {
  for (std::size_t k = 0; k < layout.size(); ++k) {
    const ParamSlot& slot = layout[k];
    if (slot.effect != se.effect) continue;
    const std::string name = param_short_name(slot.name);
    f.params.push_back({name, wheel.params(se.effect)[static_cast<std::size_t>(slot.index)]});
    double se_value = std::nan("");
    if (slot.fitted) {
      for (const FitParam& fp : sel.final_fit.params)
        if (fp.name == slot.name) se_value = fp.std_error;
    } else {
      f.discrete.push_back(name);
      se_value = se.effect == Effect::radius_step ? o.select.step_fine_s : o.select.zone_cell_m / 4.0;
    }
    f.stderrs.push_back({name, se_value});
  }
}

// The finding of one selected wheel effect: its parameters, the chosen model
// against the model without it (train and held out), and where it acts.
Finding wheel_finding(const ReplayContext& c, const Diagnosis& d, const EffectSet& wheel,
                      const std::vector<ParamSlot>& layout, const SelectedEffect& se, const ReplayResult& fin,
                      const ReplayResult& fin_s, const DiagnoseOptions& o) {
  Finding f;
  f.kind = se.effect;
  add_wheel_params(f, se, wheel, layout, d.selection, o);
  EffectSet without = wheel;
  without.disable(se.effect);
  const ReplayResult wo_s = replay(c.scoring, without, c.ws);
  f.train = scores(wo_s, fin_s, d.train_windows);
  f.heldout = scores(wo_s, fin_s, d.heldout_windows);
  f.explains = se.explains;
  f.rivals = se.rivals;
  f.evidence = d.selection.folds_are_recordings
                   ? "model selection: cross-validated by leaving one recording out, fitted with Ceres"
                   : "model selection: cross-validated over time blocks, fitted with Ceres";
  const ReplayResult wo = replay(c.in, without, c.ws);
  const Location loc = locate(residual_series(c.in, c.windows, wo), c.in.ref_sigma_m, o.locate);
  f.segments = loc.segments, f.regions = loc.regions, f.conditions = loc.phrase;
  if (f.segments.empty()) f.segments = helped_windows(wo, fin);
  if (f.conditions.empty()) f.conditions = description(se.effect);
  return f;
}

// A gyro finding scored by the fixes check's own split and windows
// (gyro_fixes_check.h): held out = its test of this parameter, train = its
// in-sample fit.
void score_gyro_via_fixes(Finding& f, const GyroFixesCheck& g, Effect effect, const Verdict& v) {
  const HeldoutComparison& h = effect == Effect::gyro_bias ? g.bias_own : g.scale_own;
  f.train = {g.nominal_pos_rmse_m, g.fitted_pos_rmse_m};
  f.heldout = {h.ref_pos_rmse_m, h.alt_pos_rmse_m};
  f.evidence = fmt::format("gyro-heading dead reckoning against the fixes over {} windows of {:g} s, {:.1f} "
                           "standard errors from the no-op value, held-out p = {:.1g}",
                           g.used_windows.size(), g.window_s, std::abs(v.z), h.p);
}

// The chosen lateral_skid acts on the gyro-heading replay too (v_y = -k v w
// with the gyro's w); the other wheel effects change travel or wheel heading,
// which this replay takes from the nominal wheels and the gyro.
EffectSet gyro_replay_body(const EffectSet& wheel) {
  EffectSet body;
  if (wheel.on(Effect::lateral_skid))
    body.enable(Effect::lateral_skid).set(Effect::lateral_skid, "k", wheel.get(Effect::lateral_skid, "k"));
  return body;
}

// Gyro findings: the sensor check against the reference heading, or with
// position fixes only, gyro-heading dead reckoning against the fixes. Each
// material one goes into the findings and the model, the others into
// `immaterial`.
void add_gyro_findings(Diagnosis& d, const ReplayContext& c, const EffectSet& wheel, const DiagnoseOptions& o) {
  const DiagInput& in = c.in;
  const bool via_fixes = !in.has_ref_heading() && !in.gyro_t_s.empty();
  if (via_fixes) {
    d.gyro_fixes = check_gyro_with_fixes(in, o.gyro_fixes);
    d.has_gyro_fixes = true;
  }
  const GyroCheck& gc = via_fixes ? d.gyro_fixes.gyro : d.sensors.gyro;
  if (!gc.available || !(gc.bias.departs() || gc.scale.departs())) return;
  const double b = gc.bias.departs() ? gc.bias.value : 0.0;
  const double s = gc.scale.departs() ? gc.scale.value : 1.0;
  const EffectSet body = gyro_replay_body(wheel);
  // Corrected by every gyro finding: the "after" of each (replayed once).
  const ReplayResult after_gyro = via_fixes ? ReplayResult{}
                                            : replay(gyro_heading_input(c.scoring, b, s), body, c.ws);
  const std::pair<Effect, const Verdict*> checks[] = {{Effect::gyro_bias, &gc.bias},
                                                      {Effect::gyro_scale, &gc.scale}};
  for (const auto& [effect, v] : checks) {
    if (!v->departs()) continue;
    Finding f;
    f.kind = effect;
    const std::string name = effect == Effect::gyro_bias ? "b" : "s";
    f.params.push_back({name, v->value});
    f.stderrs.push_back({name, v->std_error});
    if (via_fixes) {
      score_gyro_via_fixes(f, d.gyro_fixes, effect, *v);
    } else {
      const DiagInput without = effect == Effect::gyro_bias ? gyro_heading_input(c.scoring, 0.0, s)
                                                            : gyro_heading_input(c.scoring, b, 1.0);
      const ReplayResult before = replay(without, body, c.ws);
      f.train = scores(before, after_gyro, d.train_windows);
      f.heldout = scores(before, after_gyro, d.heldout_windows);
      f.evidence = fmt::format(
          "gyro against the reference yaw rate: robust regression over {} bins, {:.1f} standard "
          "errors from the no-op value",
          gc.bins, std::abs(v->z));
    }
    f.explains = f.train.before_pos_rmse_m > 0.0
                     ? std::max(0.0, 1.0 - sq(f.train.after_pos_rmse_m / f.train.before_pos_rmse_m))
                     : 0.0;
    // Its floor against the gyro-heading replay without this correction.
    const double floor_g = materiality_floor_m(in.ref_sigma_m, f.heldout.before_pos_rmse_m,
                                               o.select.materiality);
    if (!is_material(f.heldout.before_pos_rmse_m, f.heldout.after_pos_rmse_m, floor_g)) {
      d.immaterial.push_back(
          {.effect = effect,
           .line = fmt::format("{} {} = {:.3g}: removes {:.3g} mm of held-out position error, floor {:.3g} mm",
                               f.name(), name, v->value,
                               1e3 * removed_error_m(f.heldout.before_pos_rmse_m, f.heldout.after_pos_rmse_m),
                               1e3 * floor_g)});
      continue;
    }
    f.segments.push_back({in.ref_t_s.front(), in.ref_t_s.back(), 0.0, 0});
    f.conditions = description(effect);
    d.model.enable(effect).set(effect, name, v->value);
    d.findings.push_back(std::move(f));
  }
}

// What the chosen model leaves: located growth carrying a real share of
// its squared error. A finding only when something reproduces it on data
// the fit did not see (the term search, attach_term_model); growth that
// nothing predicts on held-out windows (random wheel slip, noise the model
// lacks) is listed in `not_reproduced` instead (diagnosis.h).
std::optional<Finding> located_unexplained(const Diagnosis& d, const DiagInput& in, const ReplayResult& base,
                                           const ReplayResult& fin, const DiagnoseOptions& o) {
  std::optional<Finding> located;
  const Location& la = d.located_after;
  if (la.segments.empty()) return located;
  const Inside ins = inside_segments(d.after, la.segments);
  const double share = ins.share;
  // Material too: the chosen model's held-out error must itself stand
  // unexplained_min_sigmas reference sigmas and the floor above zero (a
  // null track's 1 mm left after dead reckoning is not a finding).
  const bool material = d.heldout.after_pos_rmse_m >=
                        std::max(o.unexplained_min_sigmas * in.ref_sigma_m, d.floor_m);
  if (share >= o.unexplained_min_share && ins.rmse_m >= o.unexplained_min_sigmas * in.ref_sigma_m && material) {
    Finding f;
    f.kind = Unexplained{};
    f.segments = la.segments, f.regions = la.regions, f.conditions = la.phrase;
    // Share of the baseline's squared error that remains inside the segments.
    f.explains = base.pos_rmse_m > 0.0 ? share * sq(fin.pos_rmse_m / base.pos_rmse_m) : 0.0;
    f.train = d.train, f.heldout = d.heldout;
    f.evidence = fmt::format("the chosen model's residuals still grow faster than noise there ({:.0f} % of its "
                             "squared error)",
                             100.0 * share);
    located = std::move(f);
  }
  return located;
}

}  // namespace

bool DiagnoseOptions::IsValid(std::string* why) const {
  std::string w;
  auto part = [&](bool ok, const char* name) { return ok || core::invalid(why, std::string(name) + ": " + w); };
  if (!part(select.IsValid(&w), "select") || !part(sensors.IsValid(&w), "sensors") ||
      !part(gyro_fixes.IsValid(&w), "gyro_fixes") || !part(locate.IsValid(&w), "locate") ||
      !part(terms.IsValid(&w), "terms"))
    return false;
  return check_option_rules(
      {{is_fraction(unexplained_min_share), "unexplained_min_share", unexplained_min_share, "in [0, 1]"},
       {is_non_negative(unexplained_min_sigmas), "unexplained_min_sigmas", unexplained_min_sigmas, ">= 0"},
       {heldout_alpha > 0.0 && heldout_alpha < 1.0, "heldout_alpha", heldout_alpha, "in (0, 1)"}},
      why);
}

double Finding::param(std::string_view name) const {
  for (const NamedValue& p : params)
    if (p.name == name) return p.value;
  return std::nan("");
}

bool Finding::is_wheel_effect() const {
  const Effect* e = std::get_if<Effect>(&kind);
  return e != nullptr && !is_gyro_effect(*e);
}

std::string Finding::spec() const {
  if (is_unexplained()) return "";
  std::string s(name());
  for (std::size_t i = 0; i < params.size(); ++i)
    s += fmt::format("{}{}={}", i == 0 ? ':' : ',', params[i].name, params[i].value);
  return s;
}

Diagnosis diagnose(const DiagInput& in, const DiagnoseOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("diagnose: " + why);
  const auto t_all = Clock::now();
  Diagnosis d;
  d.track = in.track_name;
  d.reference = in.reference;
  d.ref_gt_samples = in.ref_gt_samples, d.ref_fix_samples = in.ref_fix_samples;
  d.ref_heading = in.has_ref_heading();
  d.velocity_source = in.velocity_source;
  // The selection's window (longer than fit.window_s for sparse fixes, select.h).
  const double ws = selection_window_s(in, o.select);
  d.window_s = ws;
  std::vector<Window> windows;
  try {
    windows = make_windows(in, ws);
  } catch (const std::invalid_argument&) {
    mark_too_few_samples(d, in);
    d.timing.total_s = seconds_since(t_all);
    return d;
  }

  auto t0 = Clock::now();
  d.sensors = check_sensors(in, o.sensors);
  d.timing.sensors_s = seconds_since(t0);

  t0 = Clock::now();
  d.selection = select_effects(in, o.select);
  d.timing.select_s = seconds_since(t0);
  const Selection& sel = d.selection;
  d.note = sel.note;
  const EffectSet nominal;
  // Before/after scores against the selection's denoised reference (select.h).
  const SelectionInput si = selection_input(in, o.select);
  const bool use_denoised = si.stride > 1;
  const DiagInput& scoring = use_denoised ? si.input : in;
  const ReplayContext c{in, scoring, windows, ws};
  d.scored_on_denoised_reference = use_denoised;
  t0 = Clock::now();
  const ReplayResult base = replay(in, nominal, ws);
  const ReplayResult base_s = use_denoised ? replay(scoring, nominal, ws) : base;
  d.baseline_pos_rmse_m = base.pos_rmse_m, d.baseline_heading_rmse_rad = base.heading_rmse_rad;
  d.before = residual_series(in, windows, base);
  d.located_before = locate(d.before, in.ref_sigma_m, o.locate);

  // Wheel-odometry findings (each material on the selection's cross-validated
  // held-out predictions: select.h the materiality rule and its backward pass).
  const EffectSet wheel = sel.fitted ? sel.final_fit.effects : nominal;
  set_train_heldout_split(d, sel, windows, o);
  const ReplayResult fin = replay(in, wheel, ws);
  const ReplayResult fin_s = use_denoised ? replay(scoring, wheel, ws) : fin;
  d.train = scores(base_s, fin_s, d.train_windows);
  d.heldout = scores(base_s, fin_s, d.heldout_windows);
  d.floor_m = materiality_floor_m(in.ref_sigma_m, d.heldout.before_pos_rmse_m, o.select.materiality);
  const std::vector<ParamSlot> layout = param_layout(wheel);
  for (const SelectedEffect& se : sel.effects)
    d.findings.push_back(wheel_finding(c, d, wheel, layout, se, fin, fin_s, o));
  d.final_pos_rmse_m = fin.pos_rmse_m, d.final_heading_rmse_rad = fin.heading_rmse_rad;
  d.after = residual_series(in, windows, fin);
  d.located_after = locate(d.after, in.ref_sigma_m, o.locate);
  d.model = wheel;

  add_gyro_findings(d, c, wheel, o);

  std::optional<Finding> located = located_unexplained(d, in, base, fin, o);
  const auto t_terms = Clock::now();
  attach_term_model(d, in, scoring, wheel, o, located);
  d.timing.terms_s = seconds_since(t_terms);
  std::stable_sort(d.findings.begin(), d.findings.end(),
                   [](const Finding& a, const Finding& b) { return a.explains > b.explains; });
  d.sensor_notes = reconcile_sensor_checks(d);
  d.timing.locate_s = seconds_since(t0);
  d.timing.total_s = seconds_since(t_all);
  return d;
}

}  // namespace odotune::diagnose

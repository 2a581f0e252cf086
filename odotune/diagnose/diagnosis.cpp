#include <odotune/diagnose/diagnosis.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/stopwatch.h>
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
using core::seconds_since;

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

// The train / held-out windows of the findings' numbers.
struct Split {
  std::vector<int> train, heldout;
};

// The selection's split, else its rule (last heldout_fraction of the windows).
Split train_heldout_split(const Selection& sel, std::size_t n_windows, const DiagnoseOptions& o) {
  if (sel.fitted) return {.train = sel.train_windows, .heldout = sel.heldout_windows};
  Split s;
  const auto n = static_cast<int>(n_windows);
  const int n_train = n - static_cast<int>(std::round(o.select.heldout_fraction * n));
  for (int i = 0; i < n; ++i) (i < n_train ? s.train : s.heldout).push_back(i);
  return s;
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

// The nominal and the chosen wheel model replayed on all windows, and the
// numbers of the split.
struct ModelScores {
  EffectSet wheel;         // the chosen wheel effects, fitted (nominal when none)
  ReplayResult base, fin;  // nominal and chosen, on the input
  ReplayResult fin_s;      // chosen, on the scoring input
  BeforeAfter train, heldout;
  double floor_m = 0.0;  // materiality floor against the nominal held-out error
};

ModelScores score_models(const ReplayContext& c, const Selection& sel, const Split& split,
                         const DiagnoseOptions& o) {
  const bool denoised = &c.scoring != &c.in;
  ModelScores m;
  m.wheel = sel.fitted ? sel.final_fit.effects : EffectSet();
  m.base = replay(c.in, EffectSet(), c.ws);
  const ReplayResult base_s = denoised ? replay(c.scoring, EffectSet(), c.ws) : m.base;
  m.fin = replay(c.in, m.wheel, c.ws);
  m.fin_s = denoised ? replay(c.scoring, m.wheel, c.ws) : m.fin;
  m.train = scores(base_s, m.fin_s, split.train);
  m.heldout = scores(base_s, m.fin_s, split.heldout);
  m.floor_m = materiality_floor_m(c.in.ref_sigma_m, m.heldout.before_pos_rmse_m, o.select.materiality);
  return m;
}

// Seconds spent in locate() (DiagnosisTiming::locate_s), summed over calls.
struct LocateClock {
  double seconds = 0.0;
  Location operator()(const ResidualSeries& s, double sigma_m, const LocateOptions& o) {
    const auto t0 = Clock::now();
    Location l = locate(s, sigma_m, o);
    seconds += seconds_since(t0);
    return l;
  }
};

// The residuals of the nominal and the chosen model and where they grow.
struct Residuals {
  ResidualSeries before, after;
  Location located_before, located_after;
};

Residuals located_residuals(const ReplayContext& c, const ModelScores& m, const DiagnoseOptions& o,
                            LocateClock& clock) {
  Residuals r;
  r.before = residual_series(c.in, c.windows, m.base);
  r.after = residual_series(c.in, c.windows, m.fin);
  r.located_before = clock(r.before, c.in.ref_sigma_m, o.locate);
  r.located_after = clock(r.after, c.in.ref_sigma_m, o.locate);
  return r;
}

// The parameters of the selected effect `se` in the chosen model `wheel`, with
// their standard errors (a discrete parameter's: a quarter of its zone cell, or
// the step search's fine step).
void add_wheel_params(Finding& f, const SelectedEffect& se, const EffectSet& wheel,
                      const std::vector<ParamSlot>& layout, const Selection& sel, const DiagnoseOptions& o) {
  for (const ParamSlot& slot : layout) {
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
Finding wheel_finding(const ReplayContext& c, const Selection& sel, const Split& split, const ModelScores& m,
                      const std::vector<ParamSlot>& layout, const SelectedEffect& se, const DiagnoseOptions& o,
                      LocateClock& clock) {
  Finding f;
  f.kind = se.effect;
  add_wheel_params(f, se, m.wheel, layout, sel, o);
  EffectSet without = m.wheel;
  without.disable(se.effect);
  const ReplayResult wo_s = replay(c.scoring, without, c.ws);
  f.train = scores(wo_s, m.fin_s, split.train);
  f.heldout = scores(wo_s, m.fin_s, split.heldout);
  f.explains = se.explains;
  f.rivals = se.rivals;
  f.evidence = sel.folds_are_recordings
                   ? "model selection: cross-validated by leaving one recording out, fitted with Ceres"
                   : "model selection: cross-validated over time blocks, fitted with Ceres";
  const ReplayResult wo = replay(c.in, without, c.ws);
  const Location loc = clock(residual_series(c.in, c.windows, wo), c.in.ref_sigma_m, o.locate);
  f.segments = loc.segments;
  f.regions = loc.regions;
  f.conditions = loc.phrase;
  if (f.segments.empty()) f.segments = helped_windows(wo, m.fin);
  if (f.conditions.empty()) f.conditions = effect_description(se.effect);
  return f;
}

// Wheel-odometry findings (each material on the selection's cross-validated
// held-out predictions: select.h the materiality rule and its backward pass).
std::vector<Finding> wheel_findings(const ReplayContext& c, const Selection& sel, const Split& split,
                                    const ModelScores& m, const DiagnoseOptions& o, LocateClock& clock) {
  const std::vector<ParamSlot> layout = param_layout(m.wheel);
  std::vector<Finding> out;
  for (const SelectedEffect& se : sel.effects)
    out.push_back(wheel_finding(c, sel, split, m, layout, se, o, clock));
  return out;
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

// What the gyro findings are judged by: the sensor check against the
// reference heading, or with position fixes only, gyro-heading dead
// reckoning against the fixes (gyro_fixes_check.h).
struct GyroEvidence {
  bool via_fixes = false;
  GyroFixesCheck fixes;  // set when via_fixes
  GyroCheck check;       // the check judged: fixes.gyro, or the sensor check's
};

GyroEvidence gyro_evidence(const DiagInput& in, const SensorCheck& sensors, const DiagnoseOptions& o) {
  GyroEvidence g;
  g.via_fixes = !in.has_ref_heading() && !in.gyro_t_s.empty();
  if (g.via_fixes) g.fixes = check_gyro_with_fixes(in, o.gyro_fixes);
  g.check = g.via_fixes ? g.fixes.gyro : sensors.gyro;
  return g;
}

// The gyro findings (diagnosis.h): the material ones, and a line for each
// departing check that is not material.
struct GyroFindings {
  std::vector<Finding> findings;  // material, each enabled in the model
  std::vector<ImmaterialEffect> immaterial;
};

// The finding of one departing gyro check `v` of `effect`, scored against
// the reference heading's gyro-heading replay (after: corrected by every
// departing check, b and s) or by the fixes check.
Finding gyro_finding(const ReplayContext& c, const GyroEvidence& g, Effect effect, const Verdict& v, double b,
                     double s, const EffectSet& body, const ReplayResult& after_gyro, const Split& split) {
  Finding f;
  f.kind = effect;
  const std::string name = effect == Effect::gyro_bias ? "b" : "s";
  f.params.push_back({name, v.value});
  f.stderrs.push_back({name, v.std_error});
  if (g.via_fixes) {
    score_gyro_via_fixes(f, g.fixes, effect, v);
  } else {
    const DiagInput without = effect == Effect::gyro_bias ? gyro_heading_input(c.scoring, 0.0, s)
                                                          : gyro_heading_input(c.scoring, b, 1.0);
    const ReplayResult before = replay(without, body, c.ws);
    f.train = scores(before, after_gyro, split.train);
    f.heldout = scores(before, after_gyro, split.heldout);
    f.evidence = fmt::format(
        "gyro against the reference yaw rate: robust regression over {} bins, {:.1f} standard "
        "errors from the no-op value",
        g.check.bins, std::abs(v.z));
  }
  f.explains = f.train.before_pos_rmse_m > 0.0
                   ? std::max(0.0, 1.0 - sq(f.train.after_pos_rmse_m / f.train.before_pos_rmse_m))
                   : 0.0;
  return f;
}

GyroFindings gyro_findings(const ReplayContext& c, const GyroEvidence& g, const EffectSet& wheel,
                           const Split& split, const DiagnoseOptions& o) {
  GyroFindings out;
  const GyroCheck& gc = g.check;
  if (!gc.available || !(gc.bias.departs() || gc.scale.departs())) return out;
  const double b = gc.bias.departs() ? gc.bias.value : 0.0;
  const double s = gc.scale.departs() ? gc.scale.value : 1.0;
  const EffectSet body = gyro_replay_body(wheel);
  // Corrected by every gyro finding: the "after" of each (replayed once).
  const ReplayResult after_gyro = g.via_fixes ? ReplayResult{}
                                              : replay(gyro_heading_input(c.scoring, b, s), body, c.ws);
  const std::pair<Effect, const Verdict*> checks[] = {{Effect::gyro_bias, &gc.bias},
                                                      {Effect::gyro_scale, &gc.scale}};
  for (const auto& [effect, v] : checks) {
    if (!v->departs()) continue;
    Finding f = gyro_finding(c, g, effect, *v, b, s, body, after_gyro, split);
    // Its floor against the gyro-heading replay without this correction.
    const double floor_g = materiality_floor_m(c.in.ref_sigma_m, f.heldout.before_pos_rmse_m,
                                               o.select.materiality);
    if (!is_material(f.heldout.before_pos_rmse_m, f.heldout.after_pos_rmse_m, floor_g)) {
      out.immaterial.push_back(
          {.effect = effect,
           .line = fmt::format("{} {} = {:.3g}: removes {:.3g} mm of held-out position error, floor {:.3g} mm",
                               f.name(), f.params.front().name, v->value,
                               1e3 * removed_error_m(f.heldout.before_pos_rmse_m, f.heldout.after_pos_rmse_m),
                               1e3 * floor_g)});
      continue;
    }
    f.segments.push_back({c.in.ref_t_s.front(), c.in.ref_t_s.back(), 0.0, 0});
    f.conditions = effect_description(effect);
    out.findings.push_back(std::move(f));
  }
  return out;
}

// The chosen wheel model with the material gyro findings' corrections.
EffectSet chosen_model(const EffectSet& wheel, const std::vector<Finding>& gyro) {
  EffectSet model = wheel;
  for (const Finding& f : gyro) {
    const NamedValue& p = f.params.front();
    model.enable(f.effect()).set(f.effect(), p.name, p.value);
  }
  return model;
}

// What the chosen model leaves: located growth carrying a real share of
// its squared error. A finding only when something reproduces it on data
// the fit did not see (the term search, term_findings); growth that
// nothing predicts on held-out windows (random wheel slip, noise the model
// lacks) is listed in `not_reproduced` instead (diagnosis.h).
std::optional<Finding> located_unexplained(const DiagInput& in, const Residuals& r, const ModelScores& m,
                                           const DiagnoseOptions& o) {
  const Location& la = r.located_after;
  if (la.segments.empty()) return std::nullopt;
  const Inside ins = inside_segments(r.after, la.segments);
  const double share = ins.share;
  // Material too: the chosen model's held-out error must itself stand
  // unexplained_min_sigmas reference sigmas and the floor above zero (a
  // null track's 1 mm left after dead reckoning is not a finding).
  const bool material = m.heldout.after_pos_rmse_m >=
                        std::max(o.unexplained_min_sigmas * in.ref_sigma_m, m.floor_m);
  if (!(share >= o.unexplained_min_share && ins.rmse_m >= o.unexplained_min_sigmas * in.ref_sigma_m &&
        material))
    return std::nullopt;
  return Finding{.kind = Unexplained{},
                 .params = {},
                 .stderrs = {},
                 .discrete = {},
                 .segments = la.segments,
                 .regions = la.regions,
                 .conditions = la.phrase,
                 // Share of the baseline's squared error that remains inside the segments.
                 .explains = m.base.pos_rmse_m > 0.0 ? share * sq(m.fin.pos_rmse_m / m.base.pos_rmse_m) : 0.0,
                 .train = m.train,
                 .heldout = m.heldout,
                 .rivals = {},
                 .evidence = fmt::format(
                     "the chosen model's residuals still grow faster than noise there ({:.0f} % of its "
                     "squared error)",
                     100.0 * share),
                 .model = std::nullopt,
                 .heldout_test = std::nullopt};
}

// Physics outside the list (term_search.h): terms that reproduce what the
// chosen model leaves, on the scoring input's windows and split; an input
// the search cannot use gives no model and the reason.
TermSearchResult term_search(const ReplayContext& c, const ModelScores& m, const Split& split,
                             const DiagnoseOptions& o) {
  TermSearchResult r;
  if (!o.terms.enabled || split.train.empty()) return r;
  try {
    r = search_terms(c.scoring, m.wheel, make_windows(c.scoring, c.ws), split.train, split.heldout, m.floor_m,
                     o.terms);
  } catch (const std::invalid_argument& e) {
    r.reason = std::string("term search not run: ") + e.what();
  }
  return r;
}

// The `unexplained` finding and what is not one.
struct UnexplainedFinding {
  std::optional<Finding> finding;
  std::vector<std::string> not_reproduced;
};

// A term model that passes the materiality floor goes on the `unexplained`
// finding: the located one or, when nothing was located, one made here.
// Located growth that no term reproduces on the held-out windows is not a
// finding: it goes to `not_reproduced` (diagnosis.h).
UnexplainedFinding unexplained_finding(const DiagInput& in, std::optional<Finding> located,
                                       const TermSearchResult& ts, const ModelScores& m) {
  UnexplainedFinding out;
  if (!ts.found) {
    if (located)
      out.not_reproduced.push_back(fmt::format(
          "unexplained: the chosen model's residuals grow faster than noise ({}), but no term "
          "reproduces that on held-out windows: random wheel slip or sensor noise, nothing to model",
          located->conditions.empty() ? "in places" : located->conditions));
    return out;
  }
  const TermModel& tm = ts.model;
  if (!located) {
    // Share of the nominal model's training error the terms remove.
    const double nominal = m.train.before_pos_rmse_m;
    located = Finding{.kind = Unexplained{},
                      .params = {},
                      .stderrs = {},
                      .discrete = {},
                      .segments = {{in.ref_t_s.front(), in.ref_t_s.back(), 0.0, 0}},
                      .regions = {},
                      .conditions = {},
                      .explains = nominal > 0.0 ? std::max(0.0, (sq(tm.train.before_pos_rmse_m) -
                                                                 sq(tm.train.after_pos_rmse_m)) /
                                                                    sq(nominal))
                                                : 0.0,
                      .train = {tm.train.before_pos_rmse_m, tm.train.after_pos_rmse_m},
                      .heldout = {tm.heldout.before_pos_rmse_m, tm.heldout.after_pos_rmse_m},
                      .rivals = {},
                      .evidence = {},
                      .model = std::nullopt,
                      .heldout_test = std::nullopt};
  }
  Finding& f = *located;
  f.conditions = (f.conditions.empty() ? "" : f.conditions + "; ") + tm.conditions;
  f.evidence = (f.evidence.empty() ? "" : f.evidence + "; ") +
               fmt::format("a sparse regression over {} candidate terms, chosen by cross-validation, "
                           "lowers the held-out position error from {:.4f} m to {:.4f} m",
                           ts.library_size, tm.heldout.before_pos_rmse_m, tm.heldout.after_pos_rmse_m);
  f.model = tm;
  out.finding = std::move(located);
  return out;
}

// Every finding, by importance, and what is not one (diagnosis.h): the wheel
// effects, the gyro effects, then the `unexplained` one; the chosen model.
struct Found {
  std::vector<Finding> findings;
  EffectSet model;  // the chosen wheel effects and the material gyro corrections
  GyroEvidence gyro;
  std::vector<ImmaterialEffect> immaterial;
  TermSearchResult terms;
  std::vector<std::string> not_reproduced;
  double terms_s = 0.0;  // the term search's wall-clock seconds
};

Found find_all(const ReplayContext& c, const Selection& sel, const Split& split, const ModelScores& m,
               const Residuals& r, const SensorCheck& sensors, const DiagnoseOptions& o, LocateClock& clock) {
  Found out;
  out.findings = wheel_findings(c, sel, split, m, o, clock);
  out.gyro = gyro_evidence(c.in, sensors, o);
  GyroFindings gyro = gyro_findings(c, out.gyro, m.wheel, split, o);
  out.model = chosen_model(m.wheel, gyro.findings);
  std::move(gyro.findings.begin(), gyro.findings.end(), std::back_inserter(out.findings));
  out.immaterial = std::move(gyro.immaterial);

  std::optional<Finding> located = located_unexplained(c.in, r, m, o);
  const auto t0 = Clock::now();
  out.terms = term_search(c, m, split, o);
  out.terms_s = seconds_since(t0);
  UnexplainedFinding unexplained = unexplained_finding(c.in, std::move(located), out.terms, m);
  if (unexplained.finding) out.findings.push_back(std::move(*unexplained.finding));
  out.not_reproduced = std::move(unexplained.not_reproduced);
  std::stable_sort(out.findings.begin(), out.findings.end(),
                   [](const Finding& a, const Finding& b) { return a.explains > b.explains; });
  return out;
}

// The diagnosis of an input with too few reference samples to score any
// window: no finding, said plainly.
Diagnosis too_few_samples(const DiagInput& in, double ws) {
  const double nan = std::nan("");
  Diagnosis d;
  d.track = in.track_name;
  d.reference = in.reference;
  d.ref_gt_samples = in.ref_gt_samples;
  d.ref_fix_samples = in.ref_fix_samples;
  d.ref_heading = in.has_ref_heading();
  d.velocity_source = in.velocity_source;
  d.window_s = ws;
  d.baseline_pos_rmse_m = d.baseline_heading_rmse_rad = d.final_pos_rmse_m = d.final_heading_rmse_rad = nan;
  d.note = fmt::format("{} reference sample(s) ({} ground truth, {} fixes): too few to compare a model against "
                       "(a window needs {}); no finding",
                       in.ref_t_s.size(), in.ref_gt_samples, in.ref_fix_samples,
                       in.has_ref_heading() ? "2 poses" : "3 positions");
  return d;
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
  DiagnosisTiming timing;
  // The selection's window (longer than fit.window_s for sparse fixes, select.h).
  const double ws = selection_window_s(in, o.select);
  std::vector<Window> windows;
  try {
    windows = make_windows(in, ws);
  } catch (const std::invalid_argument&) {
    Diagnosis d = too_few_samples(in, ws);
    d.timing.total_s = seconds_since(t_all);
    return d;
  }

  auto t0 = Clock::now();
  SensorCheck sensors = check_sensors(in, o.sensors);
  timing.sensors_s = seconds_since(t0);

  t0 = Clock::now();
  // Built once: the selection searches on it, the findings are scored on it.
  const SelectionInput si = selection_input(in, o.select);
  Selection sel = select_effects(in, si, o.select);
  timing.select_s = seconds_since(t0);

  // Before/after scores against the selection's denoised reference (select.h).
  const bool denoised = si.stride > 1;
  const ReplayContext c{in, denoised ? si.input : in, windows, ws};
  const Split split = train_heldout_split(sel, windows.size(), o);
  const ModelScores m = score_models(c, sel, split, o);
  LocateClock locate_clock;
  Residuals r = located_residuals(c, m, o, locate_clock);
  Found found = find_all(c, sel, split, m, r, sensors, o, locate_clock);
  timing.locate_s = locate_clock.seconds;
  timing.terms_s = found.terms_s;

  std::string note = sel.note;
  Diagnosis d{.track = in.track_name,
              .reference = in.reference,
              .ref_gt_samples = in.ref_gt_samples,
              .ref_fix_samples = in.ref_fix_samples,
              .ref_heading = in.has_ref_heading(),
              .velocity_source = in.velocity_source,
              .sensor_notes = {},  // below, from the assembled value
              .window_s = ws,
              .baseline_pos_rmse_m = m.base.pos_rmse_m,
              .baseline_heading_rmse_rad = m.base.heading_rmse_rad,
              .final_pos_rmse_m = m.fin.pos_rmse_m,
              .final_heading_rmse_rad = m.fin.heading_rmse_rad,
              .train = m.train,
              .heldout = m.heldout,
              .scored_on_denoised_reference = denoised,
              .findings = std::move(found.findings),
              .model = std::move(found.model),
              .train_windows = split.train,
              .heldout_windows = split.heldout,
              .selection = std::move(sel),
              .sensors = std::move(sensors),
              .has_gyro_fixes = found.gyro.via_fixes,
              .gyro_fixes = std::move(found.gyro.fixes),
              .before = std::move(r.before),
              .after = std::move(r.after),
              .located_before = std::move(r.located_before),
              .located_after = std::move(r.located_after),
              .term_search = std::move(found.terms),
              .timing = timing,
              .note = std::move(note),
              .floor_m = m.floor_m,
              .immaterial = std::move(found.immaterial),
              .not_reproduced = std::move(found.not_reproduced),
              .not_confirmed = {}};             // diagnose_recordings' (recordings.h)
  d.sensor_notes = reconcile_sensor_checks(d);  // reads the assembled findings, checks and records
  d.timing.total_s = seconds_since(t_all);
  return d;
}

}  // namespace odotune::diagnose

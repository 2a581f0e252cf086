#include <odotune/diagnose/select.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include <odotune/core/robust_stats.h>
#include <odotune/core/why.h>
#include <odotune/diagnose/cross_validate.h>
#include <odotune/diagnose/materiality.h>
#include <odotune/diagnose/select_search.h>
#include <odotune/diagnose/window_replay.h>
#include <odotune/diagnose/zone_boxes.h>

namespace odotune::diagnose {

using namespace select_detail;  // the search's internals (select_search.h)

namespace {

std::vector<Effect> candidate_list(const DiagInput& in, const SelectOptions& o) {
  std::vector<Effect> list = o.candidates;
  if (list.empty()) {
    list = {Effect::radius_error, Effect::wheel_base_error,  Effect::radius_step, Effect::speed_radius,
            Effect::lateral_skid, Effect::longitudinal_slip, Effect::slip_zone,   Effect::time_offset,
            Effect::actuator_lag, Effect::odometry_bias};
  }
  const bool commands = in.odometry == OdometryKind::body_velocity ||
                        (!in.cmd_v_mps.empty() && in.cmd_v_mps.size() == in.odo_t_s.size());
  std::erase_if(list, [&](Effect e) { return e == Effect::actuator_lag && !commands; });
  return list;
}

// Normalised SSE of a FitSummary's window scores (before or after).
double summary_sse(const SetScore& s, const std::vector<Window>& w, bool heading, double ism, double ish,
                   bool after) {
  double sse = 0.0;
  for (const WindowScore& ws : s.windows) {
    const Window& win = w[static_cast<std::size_t>(ws.window)];
    const auto n = static_cast<double>(win.ref_end - win.ref_begin);
    const double p = after ? ws.after_pos_rmse_m : ws.before_pos_rmse_m;
    const double h = after ? ws.after_heading_rmse_rad : ws.before_heading_rmse_rad;
    sse += n * (p * p * ism * ism + (heading ? h * h * ish * ish : 0.0));
  }
  return sse;
}

// Per window, the scored reference samples where an intermittent effect of
// s acts (after radius_step.t; inside the slip_zone box), one row per such
// effect.
std::vector<std::vector<double>> acting_samples(const DiagInput& in, const std::vector<Window>& windows,
                                                const EffectSet& s) {
  std::vector<std::vector<double>> out;
  for (Effect e : {Effect::radius_step, Effect::slip_zone}) {
    if (!s.on(e)) continue;
    std::vector<double> row;
    for (const Window& w : windows) {
      double n = 0.0;
      for (std::size_t g = w.ref_begin; g < w.ref_end; ++g)
        n += (e == Effect::radius_step ? in.ref_t_s[g] > s.get(e, "t")
                                       : in.ref_x_m[g] >= s.get(e, "x0") && in.ref_x_m[g] <= s.get(e, "x1") &&
                                             in.ref_y_m[g] >= s.get(e, "y0") && in.ref_y_m[g] <= s.get(e, "y1"))
                 ? 1.0
                 : 0.0;
      row.push_back(n);
    }
    out.push_back(std::move(row));
  }
  return out;
}

// Whether the training windows hold at least half of the samples where each
// intermittent effect acts, and the held-out ones some of them.
bool covers(const std::vector<std::vector<double>>& acting, const std::vector<int>& train,
            const std::vector<int>& held) {
  for (const auto& row : acting) {
    double tr = 0.0, ho = 0.0;
    for (int w : train) tr += row[static_cast<std::size_t>(w)];
    for (int w : held) ho += row[static_cast<std::size_t>(w)];
    if (!(2.0 * tr >= tr + ho && ho > 0.0)) return false;
  }
  return true;
}

// The windows of a split of n: phase < 0, the last n_held held out; else
// n_held spread evenly, the pattern rotated by `phase` windows.
void split_at(int phase, int n, int n_held, std::vector<int>& train, std::vector<int>& held) {
  train.clear();
  held.clear();
  for (int w = 0; w < n; ++w) {
    const long r = (w + std::max(phase, 0)) % n;
    const bool h = phase < 0 ? w >= n - n_held : (r + 1) * n_held / n > r * n_held / n;
    (h ? held : train).push_back(w);
  }
}

// The final fit of sel.structure from `start` and its split (select.h): the
// last windows held out, else (when those do not cover where each effect
// acts, or the fit is rank deficient) the first interleaved rotation that
// covers.
void fit_final(const DiagInput& raw, const DiagInput& fit_in, const std::vector<Window>& windows,
               const SelectOptions& o, const EffectSet& start, Selection& sel) {
  const EffectSet& s = sel.structure;
  FitOptions fo_final = o.fit;
  fo_final.score_before_at = s;  // scores nominal -> fitted
  const int n = static_cast<int>(windows.size());
  const int n_held = std::clamp(static_cast<int>(std::lround(o.heldout_fraction * n)), 1, n - 1);
  const auto acting = acting_samples(raw, windows, s);
  split_at(-1, n, n_held, sel.train_windows, sel.heldout_windows);
  sel.split = "last";
  bool alt_split = !covers(acting, sel.train_windows, sel.heldout_windows);
  if (!alt_split) {
    ++sel.timing.fits;
    sel.final_fit = fit_effects(fit_in, start, sel.train_windows, sel.heldout_windows, fo_final);
    alt_split = sel.final_fit.rank_deficient;
  }
  if (alt_split) {
    std::vector<int> tr, ho;
    int phase = 0;  // the first rotation that covers, else none
    for (int p = 0; p < n; ++p) {
      split_at(p, n, n_held, tr, ho);
      if (covers(acting, tr, ho)) {
        phase = p;
        break;
      }
    }
    split_at(phase, n, n_held, tr, ho);
    ++sel.timing.fits;
    FitSummary f = fit_effects(fit_in, start, tr, ho, fo_final);
    if (!f.rank_deficient || sel.final_fit.params.empty()) {
      sel.final_fit = std::move(f);
      sel.train_windows = tr;
      sel.heldout_windows = ho;
      sel.split = "interleaved";
    }
  }
}

// sel.effects: each chosen effect with the share of the final fit's training
// error it explains (the refit without it, in parallel; training scores only,
// no standard errors), most first.
void add_explained_shares(const DiagInput& fit_in, const SelectOptions& o, const std::vector<Effect>& chosen,
                          const EffectSet& start, Selection& sel) {
  const std::vector<Window> fw = make_windows(fit_in, o.fit.window_s);
  const bool heading = fit_in.has_ref_heading() && o.fit.use_heading;
  const double ism = 1.0 / fit_in.ref_sigma_m, ish = heading ? 1.0 / fit_in.ref_sigma_rad : 0.0;
  const double base = summary_sse(sel.final_fit.train, fw, heading, ism, ish, false);
  const double with_all = summary_sse(sel.final_fit.train, fw, heading, ism, ish, true);
  // The refits without each effect, in parallel (training scores only: no standard errors).
  std::vector<double> sse(chosen.size(), base);
  FitOptions fo = o.fit;
  fo.standard_errors = false;
  const auto n_chosen = static_cast<long>(chosen.size());
  std::vector<std::exception_ptr> failed(chosen.size());  // rethrown in order, outside the threads
#pragma omp parallel for schedule(dynamic, 1) if (n_chosen > 1)
  for (long i = 0; i < n_chosen; ++i) {
    EffectSet without = start;
    without.disable(chosen[static_cast<std::size_t>(i)]);
    try {
      if (!without.empty())
        sse[static_cast<std::size_t>(i)] = summary_sse(
            fit_effects(fit_in, without, sel.train_windows, {}, fo).train, fw, heading, ism, ish, true);
    } catch (...) {
      failed[static_cast<std::size_t>(i)] = std::current_exception();
    }
  }
  for (const std::exception_ptr& f : failed)
    if (f) std::rethrow_exception(f);
  for (std::size_t i = 0; i < chosen.size(); ++i) {
    if (chosen.size() > 1) ++sel.timing.fits;
    sel.effects.push_back({chosen[i], base > 0.0 ? std::clamp((sse[i] - with_all) / base, 0.0, 1.0) : 0.0, {}});
  }
  std::stable_sort(sel.effects.begin(), sel.effects.end(),
                   [](const SelectedEffect& a, const SelectedEffect& b) { return a.explains > b.explains; });
}

// The final model (select.h) on the selection input `fit_in` (same windows
// as `raw`, which decides the split).
void final_model(const DiagInput& raw, const DiagInput& fit_in, const std::vector<Window>& windows,
                 const SelectOptions& o, const std::vector<Effect>& chosen, const EffectSet& warm,
                 Selection& sel) {
  // From where the search's all-window fit of the set ended: a parameter
  // started at its no-op bound (a lag's tau = 0) can stay there while
  // another effect takes its share.
  const EffectSet start = start_from(sel.structure, warm);
  fit_final(raw, fit_in, windows, o, start, sel);
  sel.fitted = true;
  add_explained_shares(fit_in, o, chosen, start, sel);
}

// The search's start: the nominal model cross-validated and fitted on all
// windows, the materiality rule's floors against its held-out dead reckoning,
// and its record of phase "baseline".
void start_from_nominal(Search& z, const DiagInput& in_full, const SelectOptions& o) {
  Selection& sel = z.sel;
  const auto t0 = Clock::now();
  z.cur_cv = z.cv.cross_validate(EffectSet(), {}, o.cv_max_iterations);
  z.cur_full = z.cv.fit_all(EffectSet(), EffectSet(), o.cv_max_iterations);
  if (!z.cur_cv.ok || !z.cur_full.ok)
    throw std::invalid_argument(fmt::format("track '{}': nominal replay failed: {}", in_full.track_name,
                                            z.cur_cv.error + z.cur_full.error));
  sel.baseline_cv_score = z.cur_cv.score;
  // The materiality rule's floors against the nominal model's held-out dead reckoning.
  const CrossValidator::Replayed nominal = z.cv.replayed(z.cur_cv);
  z.floor_m = materiality_floor_m(in_full.ref_sigma_m, nominal.pos_rmse_m, o.materiality);
  if (in_full.has_ref_heading() && std::isfinite(nominal.heading_rmse_rad))
    z.floor_rad = materiality_floor_m(in_full.ref_sigma_rad, nominal.heading_rmse_rad, o.materiality);
  sel.floor_m = z.floor_m;
  sel.floor_rad = z.floor_rad;
  SearchRecord rb;
  rb.phase = "baseline";
  rb.set = "none";
  rb.bic = z.cur_full.bic;
  rb.accepted = true;
  rb.reason = "nominal model";
  fill(rb, z.cur_cv);
  rb.time_s = seconds_since(t0);
  sel.records.push_back(rb);
}

// The search's moves in order (select.h): forward steps, backward rounds,
// pairs, swaps, radius_error preferred, look-alikes.
void search_moves(Search& z, const SelectOptions& o, const std::vector<Effect>& cands) {
  int step = 1;
  for (; step <= o.max_effects && forward_step(z, step, cands); ++step) {
  }
  for (int round = 1; z.chosen.size() >= 2 && backward_round(z, round); ++round) {
  }
  // Pairs, when what is left stays well above the floor ("Pairs").
  if (o.pairs && static_cast<int>(z.chosen.size()) + 2 <= o.max_effects + 1 &&
      z.cv.replayed(z.cur_cv).pos_rmse_m > o.pair_above_floor * z.floor_m && pair_step(z, step, cands)) {
    // Down to one effect: the pair's survivor never passed a forward step alone.
    for (int round = 1; !z.chosen.empty() && backward_round(z, round); ++round) {
    }
  }
  // Swaps, then the backward pass again (a swap can leave an effect redundant).
  if (o.swaps && z.chosen.size() >= 2 && swap_step(z, step, cands)) {
    for (int round = 1; !z.chosen.empty() && backward_round(z, round); ++round) {
    }
  }
  prefer_radius_error(z, step);
  if (o.look_alikes) look_alike_step(z, step);
}

// Each selected effect's rivals: the candidates its forward step did not beat,
// and for a lag look-alike the look-alikes that predict as well and were not chosen.
void add_rivals(Selection& sel, const Search& z) {
  for (SelectedEffect& e : sel.effects)
    for (const SearchRecord& r : sel.records)
      if (r.phase == "forward" && r.accepted && r.effects == std::vector<Effect>{e.effect})
        e.rivals.insert(e.rivals.end(), r.rivals.begin(), r.rivals.end());
  // Look-alikes that predict as well: rivals of the chosen ones among them.
  for (SelectedEffect& e : sel.effects) {
    if (std::find(std::begin(kLagLookAlikes), std::end(kLagLookAlikes), e.effect) == std::end(kLagLookAlikes))
      continue;
    for (Effect r : z.look_alikes) {
      const bool chosen = std::find(z.chosen.begin(), z.chosen.end(), r) != z.chosen.end();
      if (!chosen && std::find(e.rivals.begin(), e.rivals.end(), r) == e.rivals.end()) e.rivals.push_back(r);
    }
  }
}

}  // namespace

bool SelectOptions::IsValid(std::string* why) const {
  std::string w;
  if (!fit.IsValid(&w)) return core::invalid(why, "fit: " + w);
  if (!materiality.IsValid(&w)) return core::invalid(why, "materiality: " + w);
  if (!(pair_above_floor >= 1.0))
    return core::invalid(why, fmt::format("pair_above_floor = {}; expected >= 1", pair_above_floor));
  if (!(fit.window_s > 0.0))
    return core::invalid(why, fmt::format("fit.window_s = {}; selection needs windows: expected > 0 s",
                                          fit.window_s));
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const Effect e = candidates[i];
    if (static_cast<int>(e) < 0 || static_cast<int>(e) >= kNumEffects)
      return core::invalid(why, fmt::format("candidates[{}] is not an effect", i));
    if (e == Effect::gyro_bias || e == Effect::gyro_scale)
      return core::invalid(why,
                           fmt::format("candidate {} acts on the gyro, not on dead reckoning", effect_name(e)));
    if (std::count(candidates.begin(), candidates.end(), e) > 1)
      return core::invalid(why, fmt::format("candidate {} listed twice", effect_name(e)));
  }
  const double coarse = step_coarse_s > 0.0 ? step_coarse_s : 0.5 * std::min(step_head_s, fit.window_s);
  // name, value, lower, upper, lower/upper included
  const struct {
    const char* name;
    double v, lo, hi;
    bool lo_in, hi_in;
  } ranges[] = {{"folds", double(folds), 2, 100, true, true},
                {"max_effects", double(max_effects), 0, kNumEffects, true, true},
                {"tries_per_step", double(tries_per_step), 1, kNumEffects, true, true},
                {"alpha", alpha, 0, 0.5, false, false},
                {"min_rel_improvement", min_rel_improvement, 0, 1, true, false},
                {"min_gain", min_gain, 0, 1e300, true, true},
                {"heldout_fraction", heldout_fraction, 0, 0.9, false, true},
                {"cv_max_iterations", double(cv_max_iterations), 1, 100000, true, true},
                {"profile_max_iterations", double(profile_max_iterations), 1, 100000, true, true},
                {"min_window_samples", min_window_samples, 0, 1e6, true, true},
                {"select_ref_rate_hz", select_ref_rate_hz, 0, 1e300, true, true},
                {"smooth_half_s", smooth_half_s, 0, 10, true, true},
                {"smooth_heading_half_s", smooth_heading_half_s, 0, 10, true, true},
                {"step_head_s", step_head_s, 0, 1e300, false, true},
                {"step_coarse_s", step_coarse_s, 0, 1e300, true, true},
                {"step_fine_s (at most a fifth of the coarse step)", step_fine_s, 0, coarse / 5.0, false, true},
                {"zone_cell_m", zone_cell_m, 0, 1e300, false, true},
                {"zone_max_boxes", double(zone_max_boxes), 0, 100, true, true},
                {"zone_min_score", zone_min_score, 0, 1e300, true, true}};
  for (const auto& r : ranges) {
    const bool ok = std::isfinite(r.v) && (r.lo_in ? r.v >= r.lo : r.v > r.lo) &&
                    (r.hi_in ? r.v <= r.hi : r.v < r.hi);
    if (!ok)
      return core::invalid(why, fmt::format("{} = {}; expected a number in {}{}, {}{}", r.name, r.v,
                                            r.lo_in ? "[" : "(", r.lo,
                                            r.hi >= 1e300 ? "inf" : fmt::format("{}", r.hi),
                                            r.hi_in && r.hi < 1e300 ? "]" : ")"));
  }
  for (std::size_t i = 0; i < zone_boxes.size(); ++i) {
    const ZoneBox& b = zone_boxes[i];
    if (!(std::isfinite(b.x0_m) && std::isfinite(b.x1_m) && std::isfinite(b.y0_m) && std::isfinite(b.y1_m) &&
          b.x0_m < b.x1_m && b.y0_m < b.y1_m))
      return core::invalid(why,
                           fmt::format("zone_boxes[{}] = [{}, {}] x [{}, {}]; expected finite x0 < x1, y0 < y1",
                                       i, b.x0_m, b.x1_m, b.y0_m, b.y1_m));
  }
  return true;
}

double selection_window_s(const DiagInput& in, const SelectOptions& o) {
  if (in.has_ref_heading() || o.min_window_samples <= 0 || in.ref_t_s.size() < 3 || in.odo_t_s.empty())
    return o.fit.window_s;
  const double period = core::median_period_s(in.ref_t_s, core::MedianRule::upper_middle);
  const double span = in.ref_t_s.back() - std::max(in.ref_t_s.front(), in.odo_t_s.front());
  const double want = o.min_window_samples * period;
  return std::max(o.fit.window_s, std::min(want, span / 3.0));
}

SelectionInput selection_input(const DiagInput& in, const SelectOptions& o) {
  const double window_s = selection_window_s(in, o);
  SelectionInput si;
  double correlated = 1.0;
  const int stride = denoised_reference(in, o.select_ref_rate_hz, o.smooth_half_s, o.smooth_heading_half_s,
                                        o.fit.model, si.input, correlated);
  if (stride > 1) {
    // The raw input's windows (its gap rule reads the reference's own period).
    si.input.fixed_window_starts_s = window_starts(in, window_s);
    si.input.fixed_window_s = window_s;
    const std::vector<Window> wf = make_windows(in, window_s), wt = make_windows(si.input, window_s);
    bool same = wt.size() == wf.size();
    for (std::size_t i = 0; same && i < wt.size(); ++i)
      same = std::abs(wt[i].t_begin_s - wf[i].t_begin_s) < 1e-9;
    if (same) {
      si.stride = stride;
      si.correlated = correlated;
      return si;
    }
  }
  si.input = in;
  return si;
}

Selection select_effects(const DiagInput& in, const SelectOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("select options: " + why);
  // Fewer than 3 windows: the selection stops before it reads the selection input.
  const bool searched = make_windows(in, selection_window_s(in, o)).size() >= 3;
  return select_effects(
      in, searched ? selection_input(in, o) : SelectionInput{.input = in, .stride = 1, .correlated = 1.0}, o);
}

Selection select_effects(const DiagInput& in_full, const SelectionInput& si, const SelectOptions& o_in) {
  std::string why;
  if (!o_in.IsValid(&why)) throw std::invalid_argument("select options: " + why);
  const auto t_start = Clock::now();
  SelectOptions o = o_in;
  o.fit.window_s = selection_window_s(in_full, o_in);
  Selection sel;
  sel.window_s = o.fit.window_s;
  const std::vector<Window> windows_full = make_windows(in_full, o.fit.window_s);
  const int n_win = static_cast<int>(windows_full.size());
  sel.num_windows = n_win;
  const ReplayResult base = replay(in_full, EffectSet(), o.fit.window_s, {}, o.fit.model);
  sel.baseline_pos_rmse_m = base.pos_rmse_m;
  sel.baseline_heading_rmse_rad = base.heading_rmse_rad;
  if (n_win < 3) {
    sel.note = fmt::format("{} window(s) of {} s: too few to cross-validate (need 3)", n_win, o.fit.window_s);
    sel.timing.total_s = seconds_since(t_start);
    return sel;
  }

  const DiagInput* in = &si.input;
  sel.ref_stride = si.stride;
  CrossValidator cv(*in, o.fit, o.folds, si.correlated, o.recording_starts_s);
  sel.folds = cv.num_folds();
  sel.folds_are_recordings = cv.folds_are_recordings();
  Search z{.cv = cv,
           .o = o,
           .sel = sel,
           .s = EffectSet(),
           .chosen = {},
           .cur_cv = {},
           .cur_full = {},
           .step_t = kNaN,
           .floor_m = 0.0,
           .floor_rad = 0.0,
           .heading = in->has_ref_heading(),
           .look_alikes = {}};

  start_from_nominal(z, in_full, o);
  search_moves(z, o, candidate_list(in_full, o));
  sel.final_cv_score = z.cur_cv.score;
  sel.structure = z.s;
  sel.timing.search_s = seconds_since(t_start);
  sel.timing.fits = cv.fits();
  if (!z.chosen.empty()) {
    const auto t0 = Clock::now();
    final_model(in_full, *in, windows_full, o, z.chosen, z.cur_full.fitted, sel);
    sel.timing.final_s = seconds_since(t0);
  }
  add_rivals(sel, z);
  sel.timing.total_s = seconds_since(t_start);
  return sel;
}

}  // namespace odotune::diagnose

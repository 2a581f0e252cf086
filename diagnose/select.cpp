#include "diagnose/select.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <initializer_list>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "diagnose/cross_validate.h"
#include "diagnose/materiality.h"
#include "diagnose/window_replay.h"
#include "diagnose/zone_boxes.h"

namespace odotune::diagnose {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMaxCoarseSteps = 32.0;  // radius_step.t coarse grid (profile_step_time)

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

EffectSet with_effect(const EffectSet& s, Effect e) {
  EffectSet out = s;
  out.enable(e);
  return out;
}

// Rule (e) of select.h: the error `alt` removes from `ref`'s, position and
// (with a reference heading) heading, both measured on their held-out
// predictions replayed as dead reckoning (CrossValidator::replayed), against
// the floors of Search.
struct Removed {
  double pos_m = 0.0, heading_rad = 0.0;  // materiality.h removed_error_m of each
};
Removed removed(CrossValidator& cv, const SetEval& ref, const SetEval& alt) {
  const CrossValidator::Replayed a = cv.replayed(ref), b = cv.replayed(alt);
  return {removed_error_m(a.pos_rmse_m, b.pos_rmse_m),
          std::isfinite(a.heading_rmse_rad) && std::isfinite(b.heading_rmse_rad)
              ? removed_error_m(a.heading_rmse_rad, b.heading_rmse_rad)
              : 0.0};
}

// Material (rule (e)): "" when the removed position error passes floor_m or
// the removed heading error passes floor_rad (> 0 only with a reference
// heading); a floor_m of 0 asks nothing.
std::string immaterial(const Removed& r, double floor_m, double floor_rad) {
  if (!(floor_m > 0.0) || r.pos_m >= floor_m || (floor_rad > 0.0 && r.heading_rad >= floor_rad)) return "";
  if (floor_rad > 0.0)
    return fmt::format(
        "immaterial: removes {:.3g} mm of held-out position error (floor {:.3g} mm) and {:.3g} mrad of "
        "heading error (floor {:.3g} mrad)",
        1e3 * r.pos_m, 1e3 * floor_m, 1e3 * r.heading_rad, 1e3 * floor_rad);
  return fmt::format("immaterial: removes {:.3g} mm of held-out position error, floor {:.3g} mm", 1e3 * r.pos_m,
                     1e3 * floor_m);
}

// Rules (a)-(c) and (e) of select.h for `alt` to beat `ref`; "" when they
// hold. gain: what alt removes from ref's CV error; floor_m, floor_rad: the
// materiality floors (floor_m 0 = not asked).
std::string verdict(const PairedComparison& p, double delta_bic, const SelectOptions& o,
                    const Removed& gain = {}, double floor_m = 0.0, double floor_rad = 0.0) {
  if (std::string why = immaterial(gain, floor_m, floor_rad); !why.empty()) return why;
  if (!(p.rel >= o.min_rel_improvement))
    return fmt::format("relative CV improvement {:.2f} % < {:.2f} %", 100.0 * p.rel,
                       100.0 * o.min_rel_improvement);
  if (!(p.gain >= o.min_gain))
    return fmt::format("CV gain {:.3g} < {:.3g} (normalised units)", p.gain, o.min_gain);
  if (!p.significant)
    return fmt::format("not significant: Wilcoxon p = {:.3g}, t p = {:.3g} (level halved), Stouffer "
                       "p = {:.3g} ({} of {} informative windows improved), level {:.3g}",
                       p.p_rank, p.p_t, p.p_param, p.improved, p.changed, o.alpha);
  if (!(delta_bic < 0.0)) return fmt::format("BIC did not decrease (change {:.4g})", delta_bic);
  return "";
}

void fill(SearchRecord& r, const SetEval& e) {
  r.cv_score = e.ok ? e.score : kNaN;
  r.cv_pos_rmse_m = e.ok ? e.pos_rmse_m : kNaN;
  r.cv_heading_rmse_rad = e.ok ? e.heading_rmse_rad : kNaN;
}
void fill(SearchRecord& r, const PairedComparison& p) {
  r.rel_improvement = p.rel, r.gain = p.gain;
  r.windows_changed = p.changed, r.windows_improved = p.improved;
  r.p_rank = p.p_rank, r.p_t = p.p_t, r.p_param = p.p_param, r.significant = p.significant;
}

// radius_step.t by profile search of the all-window fit cost (select.h).
// The points of one grid level are fitted in parallel (OpenMP), each
// warm-started from the same fit (the current set's, then the best point's
// of the level before), so the result does not depend on the thread count.
double profile_step_time(CrossValidator& cv, const EffectSet& s, const EffectSet& s_fitted, double prev_t,
                         const SelectOptions& o) {
  // Earlier, a step is a radius_error: the first step_head_s of the track, or
  // its first window when that is shorter. Not the whole first window: with
  // sparse fixes the windows grow (selection_window_s) and an 80 s first
  // window held the step of dev seed 1004's case 118 (74.2 s, found at 80).
  const Window& first = cv.windows().front();
  const double head = std::min(o.step_head_s, first.t_end_s - first.t_begin_s);
  const double lo = first.t_begin_s + head;
  const double span = cv.windows().back().t_end_s - lo;
  // At most kMaxCoarseSteps coarse steps: on long tracks the coarse step
  // grows with the track, so the count of fits (each costing the track's
  // length) stays bounded and the search costs linear time.
  const double coarse = std::max(o.step_coarse_s > 0.0 ? o.step_coarse_s : 0.5 * head, span / kMaxCoarseSteps);
  const double hi = cv.windows().back().t_end_s - 0.5 * coarse;
  if (!(hi > lo)) return kNaN;
  std::map<double, std::pair<double, EffectSet>> seen;  // t -> (cost, fitted)
  // Fits the times not seen yet, all from `warm`.
  auto costs = [&](std::vector<double> ts, const EffectSet& warm) {
    for (double& t : ts) t = std::clamp(t, lo, hi);
    std::sort(ts.begin(), ts.end());
    ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
    std::erase_if(ts, [&](double t) { return seen.count(t) > 0; });
    std::vector<std::pair<double, EffectSet>> res(ts.size(), {kInf, warm});
#pragma omp parallel for schedule(dynamic, 1) if (ts.size() > 1)
    for (std::size_t i = 0; i < ts.size(); ++i) {
      EffectSet st = with_effect(s, Effect::radius_step);
      st.set(Effect::radius_step, "t", ts[i]);
      try {
        const FitSummary f = cv.fit(start_from(st, warm), {}, o.profile_max_iterations);
        if (std::isfinite(f.final_cost)) res[i] = {f.final_cost, f.effects};
      } catch (const std::exception&) {
      }
    }
    for (std::size_t i = 0; i < ts.size(); ++i) seen[ts[i]] = std::move(res[i]);
  };
  auto best_t = [&]() {
    double bt = kNaN, bc = kInf;
    for (const auto& [t, v] : seen)
      if (v.first < bc) bc = v.first, bt = t;
    return bt;
  };
  if (std::isfinite(prev_t)) {
    costs({prev_t}, s_fitted);
  } else {
    std::vector<double> grid;
    for (double t = lo; t <= hi + 1e-9; t += coarse) grid.push_back(t);
    costs(grid, s_fitted);
  }
  // Refinement: steps of coarse/5 over +-0.6 coarse (+-0.4 from a previous
  // time), then each level a fifth of the last step (at least step_fine_s)
  // over +- the last step, down to step_fine_s.
  double step = coarse / 5.0, reach = std::isfinite(prev_t) ? 0.4 * coarse : 0.6 * coarse;
  for (;;) {
    const double centre = best_t();
    if (!std::isfinite(centre)) return kNaN;
    const int k = static_cast<int>(std::floor(reach / step + 1e-9));
    std::vector<double> ts;
    for (int i = -k; i <= k; ++i) ts.push_back(centre + i * step);
    costs(ts, seen[centre].second);
    if (step <= o.step_fine_s * (1.0 + 1e-9)) break;
    reach = step;
    step = std::max(o.step_fine_s, step / 5.0);
  }
  return best_t();
}

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

// State of the search.
struct Search {
  CrossValidator& cv;
  const SelectOptions& o;
  Selection& sel;
  EffectSet s;                 // selected structure (no-op fitted values, discrete set)
  std::vector<Effect> chosen;  // in the order accepted
  SetEval cur_cv, cur_full;    // of s
  double step_t = kNaN;        // last radius_step.t found
  double floor_m = 0.0;        // materiality floor (rule (e)) [m]
  double floor_rad = 0.0;      // its heading part [rad] (0 without a reference heading)
  bool heading = false;        // the reference has a heading
};

// Rules (a)-(e) of a candidate set `cv` (its effects `added`) against the
// current set: fits it on all windows (BIC, into rec), then asks each added
// effect's own parameters to matter (rule (d)). "" when it passes; `full`
// receives the all-window fit.
std::string judge(Search& z, const EffectSet& st, const SetEval& cv, std::initializer_list<Effect> added,
                  SearchRecord& rec, SetEval& full) {
  full = z.cv.fit_all(st, z.cur_full.fitted, z.o.cv_max_iterations);
  rec.bic = full.ok ? full.bic : kNaN;
  rec.delta_bic = full.ok ? full.bic - z.cur_full.bic : kNaN;
  if (!full.ok) return "fit on all windows failed: " + full.error;
  std::string no = verdict(z.cv.compare(z.cur_cv, cv, z.o.alpha), rec.delta_bic, z.o,
                           removed(z.cv, z.cur_cv, cv), z.floor_m, z.floor_rad);
  for (Effect e : added) {  // each new effect itself must matter (actuator_lag's no-op is another source)
    if (!no.empty()) break;
    const SetEval own = z.cv.own_noop(cv, e);
    const std::string why = own.ok ? verdict(z.cv.compare(own, cv, z.o.alpha), -1.0, z.o,
                                             removed(z.cv, own, cv), z.floor_m, z.floor_rad)
                                   : own.error;
    if (!why.empty())
      no = added.size() == 1 ? "its own parameters at their no-op values do as well: " + why
                             : fmt::format("{} at its no-op values does as well: {}", effect_name(e), why);
  }
  return no;
}

// One forward step; true when a candidate was accepted.
bool forward_step(Search& z, int step, const std::vector<Effect>& cands) {
  struct Cand {
    Effect e;
    EffectSet st;
    SetEval cv;
    SearchRecord rec;
  };
  std::vector<Cand> tried;
  std::vector<double> t_cand;  // wall time of each candidate's discrete search
  for (Effect e : cands) {
    if (std::count(z.chosen.begin(), z.chosen.end(), e)) continue;
    const auto t0 = Clock::now();
    Cand cd{e, with_effect(z.s, e), {}, {}};
    cd.rec.step = step, cd.rec.phase = "forward", cd.rec.candidate = effect_name(e);
    cd.rec.set = cd.st.to_string();
    if (e == Effect::radius_step) {
      z.step_t = profile_step_time(z.cv, z.s, z.cur_full.fitted, z.step_t, z.o);
      if (std::isfinite(z.step_t))
        cd.st.set(Effect::radius_step, "t", z.step_t);
      else
        cd.rec.reason = "no step time to try (track too short)";
    } else if (e == Effect::slip_zone) {
      cd.st = choose_zone_box(z.cv, z.s, z.cur_full,
                              {z.o.zone_cell_m, z.o.zone_max_boxes, z.o.zone_min_score, z.o.zone_boxes,
                               z.o.profile_max_iterations});
      if (cd.st.empty()) cd.rec.reason = "no candidate box";
    }
    t_cand.push_back(since(t0));
    if (e == Effect::radius_step || e == Effect::slip_zone) z.sel.timing.discrete_s += t_cand.back();
    tried.push_back(std::move(cd));
  }
  // Every candidate's cross-validation at once: the (candidate, fold) fits
  // run in parallel (CrossValidator::cross_validate_all); record times are
  // the discrete search plus the candidate's share of the batch.
  std::vector<EffectSet> sets;
  std::vector<std::size_t> which;
  for (std::size_t i = 0; i < tried.size(); ++i)
    if (tried[i].rec.reason.empty()) sets.push_back(tried[i].st), which.push_back(i);
  const auto t_batch = Clock::now();
  std::vector<SetEval> evals = z.cv.cross_validate_all(sets, z.cur_cv.folds, z.o.cv_max_iterations);
  const double share = sets.empty() ? 0.0 : since(t_batch) / static_cast<double>(sets.size());
  for (std::size_t j = 0; j < which.size(); ++j) {
    Cand& cd = tried[which[j]];
    cd.rec.set = cd.st.to_string();
    cd.cv = std::move(evals[j]);
    if (cd.cv.ok)
      fill(cd.rec, z.cv.compare(z.cur_cv, cd.cv, z.o.alpha));
    else
      cd.rec.reason = "fit failed: " + cd.cv.error;
    t_cand[which[j]] += share;
  }
  for (std::size_t i = 0; i < tried.size(); ++i) {
    fill(tried[i].rec, tried[i].cv);
    tried[i].rec.time_s = t_cand[i];
  }
  // Candidates by CV score; the best few are judged in turn (select.h,
  // "Forward step"): the first that passes every rule is accepted.
  std::vector<Cand*> order;
  for (Cand& cd : tried)
    if (cd.cv.ok) order.push_back(&cd);
  std::stable_sort(order.begin(), order.end(),
                   [](const Cand* a, const Cand* b) { return a->cv.score < b->cv.score; });
  // radius_error goes first unless `rival`, ranked before it, beats it by
  // rules (a) and (b) (select.h, "Candidates"): a radius step is a radius
  // error from a time on (nested: an early step fits a constant error's
  // noise, dev seed 1002 case 105 at 31 s of 20 s windows' head); without a
  // reference heading a yaw-rate offset bends the path as a wheel
  // differential does.
  const auto radius_error_unless_beaten = [&](Effect rival) {
    const auto at = [&](Effect e) {
      return std::find_if(order.begin(), order.end(), [e](const Cand* c) { return c->e == e; });
    };
    const auto ob = at(rival), re = at(Effect::radius_error);
    if (ob != order.end() && re != order.end() && ob < re &&
        !verdict(z.cv.compare((*re)->cv, (*ob)->cv, z.o.alpha), -1.0, z.o).empty())
      std::rotate(ob, re, re + 1);
  };
  radius_error_unless_beaten(Effect::radius_step);
  if (!z.heading) radius_error_unless_beaten(Effect::odometry_bias);
  bool accepted = false;
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    Cand* best = order[rank];
    if (rank >= static_cast<std::size_t>(z.o.tries_per_step) || accepted) {
      best->rec.reason = fmt::format("not the best of step {} (CV {:.4g} vs {:.4g})", step, best->cv.score,
                                     order.front()->cv.score);
      continue;
    }
    const auto t0 = Clock::now();
    SetEval full;
    const std::string no = judge(z, best->st, best->cv, {best->e}, best->rec, full);
    best->rec.time_s += since(t0);
    const std::string label = rank == 0 ? "best candidate"
                                        : fmt::format("best candidate that passes (rank {})", rank + 1);
    if (no.empty()) {
      accepted = best->rec.accepted = true;
      best->rec.reason = label + "; improves CV significantly and BIC agrees";
      // Confounded alternatives: candidates the winner does not beat by (a)-(b).
      for (Cand& cd : tried)
        if (cd.cv.ok && &cd != best && !verdict(z.cv.compare(cd.cv, best->cv, z.o.alpha), -1.0, z.o).empty())
          best->rec.rivals.push_back(std::string(effect_name(cd.e)));
      z.s = best->st;
      z.chosen.push_back(best->e);
      z.cur_cv = std::move(best->cv);
      z.cur_full = std::move(full);
    } else {
      best->rec.reason = (rank == 0 ? "best candidate" : fmt::format("candidate of rank {}", rank + 1)) +
                         " rejected: " + no;
    }
  }
  for (Cand& cd : tried) z.sel.records.push_back(std::move(cd.rec));
  return accepted;
}

// Without a reference heading (select.h, "Candidates"): when the selected set
// holds odometry_bias and not radius_error, the set with radius_error in its
// place is cross-validated, and swapped in unless the selected set beats it
// by rules (a) and (b) and the materiality floor. Logged as a record of
// phase "swap".
void prefer_radius_error(Search& z, int step) {
  const auto has = [&](Effect e) { return std::count(z.chosen.begin(), z.chosen.end(), e) > 0; };
  if (z.heading || !has(Effect::odometry_bias) || has(Effect::radius_error)) return;
  const auto t0 = Clock::now();
  EffectSet st = z.s;
  st.disable(Effect::odometry_bias);
  st.enable(Effect::radius_error);
  SearchRecord rec;
  rec.step = step, rec.phase = "swap", rec.candidate = "radius_error for odometry_bias";
  rec.set = st.to_string();
  SetEval cv = z.cv.cross_validate_all({st}, z.cur_cv.folds, z.o.cv_max_iterations).front();
  fill(rec, cv);
  if (!cv.ok) {
    rec.reason = "fit failed: " + cv.error;
  } else {
    const PairedComparison p = z.cv.compare(cv, z.cur_cv, z.o.alpha);  // keeping odometry_bias vs the swap
    fill(rec, p);
    const std::string beats = verdict(p, -1.0, z.o, removed(z.cv, cv, z.cur_cv), z.floor_m, z.floor_rad);
    if (beats.empty()) {
      rec.reason = "kept odometry_bias: it predicts held-out windows better than radius_error in its place";
    } else {
      SetEval full = z.cv.fit_all(st, z.cur_full.fitted, z.o.cv_max_iterations);
      if (!full.ok) {
        rec.reason = "fit on all windows failed: " + full.error;
      } else {
        rec.accepted = true;
        rec.reason = "swapped: odometry_bias does not beat radius_error in its place (" + beats + ")";
        std::replace(z.chosen.begin(), z.chosen.end(), Effect::odometry_bias, Effect::radius_error);
        z.s = st;
        z.cur_cv = std::move(cv);
        z.cur_full = std::move(full);
      }
    }
  }
  rec.time_s = since(t0);
  z.sel.records.push_back(std::move(rec));
}

// Swaps (select.h, "Swaps"): one candidate in place of two selected
// effects. Greedy steps accept the effect that predicts best now, and two
// of them can together mimic a third that was never best alone (benchmark
// dev seed 1004, case 66: a speed offset b_v = -0.027 m/s fitted as radius
// error + speed radius beside the true wheel base error). Every candidate
// without a discrete search (not radius_step, not slip_zone) in place of
// each pair of selected effects is fitted on all windows; the lowest BIC is
// cross-validated and swapped in when the selected set does not beat it by
// rules (a) and (e), as the backward pass asks of a removal, and the incoming
// effect's own parameters matter (rule (d)). (One in place of one, tried
// too on dev seed 1004, changed no case.)
// True when a swap was made; logged as records of phase "swap".
bool swap_step(Search& z, int step, const std::vector<Effect>& cands) {
  const auto chosen = [&](Effect e) { return std::count(z.chosen.begin(), z.chosen.end(), e) > 0; };
  struct Cand {
    Effect in;
    std::vector<Effect> out;
    EffectSet st;
    SearchRecord rec;
  };
  std::vector<Cand> tried;
  std::vector<std::vector<Effect>> outs;
  for (std::size_t i = 0; i < z.chosen.size(); ++i) {
    for (std::size_t j = i + 1; j < z.chosen.size(); ++j) outs.push_back({z.chosen[i], z.chosen[j]});
  }
  for (Effect c : cands) {
    if (chosen(c) || c == Effect::radius_step || c == Effect::slip_zone) continue;
    for (const std::vector<Effect>& out : outs) {
      Cand cd{c, out, z.s, {}};
      for (Effect e : out) cd.st.disable(e);
      cd.st = with_effect(cd.st, c);
      cd.rec.step = step, cd.rec.phase = "swap";
      cd.rec.candidate = fmt::format("{} for {}+{}", effect_name(c), effect_name(out[0]), effect_name(out[1]));
      cd.rec.set = cd.st.to_string();
      tried.push_back(std::move(cd));
    }
  }
  if (tried.empty()) return false;
  // Screened by one fit on all windows each (in parallel; a fifth of a
  // cross-validation): the lowest BIC is cross-validated, unless even its
  // all-window score is worse than the selected set's by rule (a)'s share.
  const auto t0 = Clock::now();
  std::vector<SetEval> fulls(tried.size());
  const auto n_tried = static_cast<long>(tried.size());
#pragma omp parallel for schedule(dynamic, 1) if (n_tried > 1)
  for (long i = 0; i < n_tried; ++i) {
    const auto k = static_cast<std::size_t>(i);
    fulls[k] = z.cv.fit_all(tried[k].st, z.cur_full.fitted, z.o.cv_max_iterations);
  }
  const double share = since(t0) / static_cast<double>(tried.size());
  std::size_t best = tried.size();
  for (std::size_t i = 0; i < tried.size(); ++i) {
    tried[i].rec.time_s = share;
    tried[i].rec.bic = fulls[i].ok ? fulls[i].bic : kNaN;
    tried[i].rec.delta_bic = fulls[i].ok ? fulls[i].bic - z.cur_full.bic : kNaN;
    if (!fulls[i].ok)
      tried[i].rec.reason = "fit on all windows failed: " + fulls[i].error;
    else if (best == tried.size() || fulls[i].bic < fulls[best].bic)
      best = i;
  }
  bool swapped = false;
  if (best < tried.size()) {
    Cand& b = tried[best];
    for (std::size_t i = 0; i < tried.size(); ++i)
      if (i != best && fulls[i].ok)
        tried[i].rec.reason = fmt::format("not the best swap (BIC on all windows {:.6g} vs {:.6g})",
                                          fulls[i].bic, fulls[best].bic);
    std::string no;
    SetEval cv;
    if (!(fulls[best].score * (1.0 - z.o.min_rel_improvement) <= z.cur_full.score)) {
      no = fmt::format("on all windows it fits {:.2f} % worse than the selected set",
                       100.0 * (fulls[best].score / z.cur_full.score - 1.0));
    } else {
      const auto t1 = Clock::now();
      cv = z.cv.cross_validate_all({b.st}, z.cur_cv.folds, z.o.cv_max_iterations).front();
      b.rec.time_s += since(t1);
      fill(b.rec, cv);
      if (!cv.ok) no = "fit failed: " + cv.error;
    }
    if (no.empty()) {
      const PairedComparison p = z.cv.compare(cv, z.cur_cv, z.o.alpha);  // keeping the selected vs the swap
      fill(b.rec, z.cv.compare(z.cur_cv, cv, z.o.alpha));
      const std::string keep = immaterial(removed(z.cv, cv, z.cur_cv), z.floor_m, z.floor_rad);
      if (keep.empty() && p.rel >= z.o.min_rel_improvement && p.gain >= z.o.min_gain)
        no = fmt::format("the selected set predicts {:.2f} % better", 100.0 * p.rel);
    }
    if (no.empty()) {
      const SetEval own = z.cv.own_noop(cv, b.in);
      const std::string why = own.ok ? verdict(z.cv.compare(own, cv, z.o.alpha), -1.0, z.o,
                                               removed(z.cv, own, cv), z.floor_m, z.floor_rad)
                                     : own.error;
      if (!why.empty()) no = fmt::format("{} at its no-op values does as well: {}", effect_name(b.in), why);
    }
    if (no.empty()) {
      swapped = b.rec.accepted = true;
      b.rec.reason = "swapped: the two it replaces do not predict held-out windows materially better";
      for (Effect e : b.out) std::erase(z.chosen, e);
      z.chosen.push_back(b.in);
      z.s = b.st;
      z.cur_cv = std::move(cv);
      z.cur_full = std::move(fulls[best]);
    } else {
      b.rec.reason = "best swap rejected: " + no;
    }
  }
  for (Cand& cd : tried) z.sel.records.push_back(std::move(cd.rec));
  return swapped;
}

// The pairs of effects the conditions of a mismatch point to (select.h,
// "Pairs"): the effect a condition names with the effect it is confounded
// with, so that two effects that only together explain the data get tried
// together.
constexpr std::pair<Effect, Effect> kConditionPairs[] = {
    {Effect::longitudinal_slip, Effect::radius_error},  // acceleration
    {Effect::speed_radius, Effect::radius_error},       // speed
    {Effect::actuator_lag, Effect::time_offset},        // velocity changes: lag vs offset
    {Effect::time_offset, Effect::radius_error},        // velocity changes
    {Effect::wheel_base_error, Effect::lateral_skid},   // turn rate
    {Effect::wheel_base_error, Effect::radius_error},   // turn rate
    {Effect::odometry_bias, Effect::radius_error},      // at rest / everywhere
};

// One pair step: every pair of kConditionPairs whose effects are candidates
// and not yet chosen is added to the current set and cross-validated; the
// best is accepted by rules (a)-(c) and (e) against the current set, and
// each of its effects must matter by rule (d). True when a pair was accepted.
bool pair_step(Search& z, int step, const std::vector<Effect>& cands) {
  auto usable = [&](Effect e) {
    return std::count(cands.begin(), cands.end(), e) > 0 &&
           std::count(z.chosen.begin(), z.chosen.end(), e) == 0;
  };
  struct Cand {
    std::pair<Effect, Effect> p;
    EffectSet st;
    SetEval cv;
    SearchRecord rec;
  };
  std::vector<Cand> tried;
  std::vector<EffectSet> sets;
  for (const auto& pr : kConditionPairs) {
    if (!usable(pr.first) || !usable(pr.second)) continue;
    Cand cd{pr, with_effect(with_effect(z.s, pr.first), pr.second), {}, {}};
    cd.rec.step = step, cd.rec.phase = "pair";
    cd.rec.candidate = fmt::format("{}+{}", effect_name(pr.first), effect_name(pr.second));
    cd.rec.set = cd.st.to_string();
    sets.push_back(cd.st);
    tried.push_back(std::move(cd));
  }
  // All pairs' (pair, fold) fits in one parallel batch, as a forward step's.
  const auto t_batch = Clock::now();
  std::vector<SetEval> evals = z.cv.cross_validate_all(sets, z.cur_cv.folds, z.o.cv_max_iterations);
  const double share = sets.empty() ? 0.0 : since(t_batch) / static_cast<double>(sets.size());
  for (std::size_t i = 0; i < tried.size(); ++i) {
    Cand& cd = tried[i];
    cd.cv = std::move(evals[i]);
    if (cd.cv.ok)
      fill(cd.rec, z.cv.compare(z.cur_cv, cd.cv, z.o.alpha));
    else
      cd.rec.reason = "fit failed: " + cd.cv.error;
    fill(cd.rec, cd.cv);
    cd.rec.time_s = share;
  }
  Cand* best = nullptr;
  for (Cand& cd : tried)
    if (cd.cv.ok && (!best || cd.cv.score < best->cv.score)) best = &cd;
  bool accepted = false;
  if (best) {
    for (Cand& cd : tried)
      if (cd.cv.ok && &cd != best)
        cd.rec.reason = fmt::format("not the best pair (CV {:.4g} vs {:.4g})", cd.cv.score, best->cv.score);
    const auto t0 = Clock::now();
    SetEval full;
    const std::string no = judge(z, best->st, best->cv, {best->p.first, best->p.second}, best->rec, full);
    best->rec.time_s += since(t0);
    if (no.empty()) {
      accepted = best->rec.accepted = true;
      best->rec.reason = "best pair; improves CV significantly and materially, BIC agrees, both effects matter";
      z.s = best->st;
      z.chosen.push_back(best->p.first);
      z.chosen.push_back(best->p.second);
      z.cur_cv = std::move(best->cv);
      z.cur_full = std::move(full);
    } else {
      best->rec.reason = "best pair rejected: " + no;
    }
  }
  for (Cand& cd : tried) z.sel.records.push_back(std::move(cd.rec));
  return accepted;
}

// One backward round; true when an effect was removed.
bool backward_round(Search& z, int round) {
  struct Drop {
    Effect e;
    EffectSet st;
    SetEval cv, full;
    SearchRecord rec;
    bool removable = false;
  };
  std::vector<Drop> drops;
  const auto t0 = Clock::now();
  std::vector<EffectSet> sets;
  for (Effect e : z.chosen) {
    Drop d{e, z.s, {}, {}, {}, false};
    d.st.disable(e);
    d.rec.step = round, d.rec.phase = "backward", d.rec.candidate = effect_name(e);
    d.rec.set = d.st.to_string();
    sets.push_back(d.st);
    drops.push_back(std::move(d));
  }
  // All removals cross-validated at once, then their all-window fits, in
  // parallel (CrossValidator is thread-safe; results independent of threads).
  std::vector<SetEval> evals = z.cv.cross_validate_all(sets, z.cur_cv.folds, z.o.cv_max_iterations);
  const auto n_drops = static_cast<long>(drops.size());
#pragma omp parallel for schedule(dynamic, 1) if (n_drops > 1)
  for (long i = 0; i < n_drops; ++i) {
    Drop& d = drops[static_cast<std::size_t>(i)];
    d.cv = std::move(evals[static_cast<std::size_t>(i)]);
    if (d.cv.ok) d.full = z.cv.fit_all(d.st, z.cur_full.fitted, z.o.cv_max_iterations);
  }
  const double share = drops.empty() ? 0.0 : since(t0) / static_cast<double>(drops.size());
  for (Drop& d : drops) {
    fill(d.rec, d.cv);
    if (d.cv.ok && d.full.ok) {
      const PairedComparison p = z.cv.compare(d.cv, z.cur_cv, z.o.alpha);  // keeping e vs dropping it
      fill(d.rec, p);
      d.rec.bic = d.full.bic;
      d.rec.delta_bic = z.cur_full.bic - d.full.bic;
      // Redundancy by rule (a) only: once another effect changes every
      // window, an intermittent effect's paired test has little power left.
      // Or by rule (e): what it gains is immaterial.
      const std::string why = immaterial(removed(z.cv, d.cv, z.cur_cv), z.floor_m, z.floor_rad);
      const bool material = why.empty();
      d.removable = !(p.rel >= z.o.min_rel_improvement && p.gain >= z.o.min_gain) || !material;
      d.rec.reason = !material ? "removable: " + why
                     : d.removable
                         ? fmt::format("removable: without it CV is only {:.2f} % worse", 100.0 * p.rel)
                         : "kept: it is needed";
      // Rule (d) again for an effect whose no-op is not its absence
      // (actuator_lag: its no-op replays the commands, not the encoders):
      // accepted within a pair, it may be left alone by the pair's other
      // effect's removal, and then its own parameters must still matter
      // (benchmark dev seed 1004, case 40: a null track's 360-cpr encoders
      // lost to the commands; actuator_lag + time_offset passed as a pair,
      // time_offset was dropped, tau = 0.14 ms stayed).
      if (!d.removable && d.e == Effect::actuator_lag) {
        const SetEval own = z.cv.own_noop(z.cur_cv, d.e);
        const std::string no = own.ok ? verdict(z.cv.compare(own, z.cur_cv, z.o.alpha), -1.0, z.o,
                                                removed(z.cv, own, z.cur_cv), z.floor_m, z.floor_rad)
                                      : own.error;
        if (!no.empty()) {
          d.removable = true;
          d.rec.rel_improvement = std::min(d.rec.rel_improvement, 0.0);
          d.rec.reason = "removable: its own parameters at their no-op values do as well: " + no;
        }
      }
    } else {
      d.rec.reason = "fit without it failed: " + d.cv.error + d.full.error;
    }
    d.rec.time_s = share;
  }
  Drop* out = nullptr;
  for (Drop& d : drops)
    if (d.removable && (!out || d.rec.rel_improvement < out->rec.rel_improvement)) out = &d;
  if (out) {
    out->rec.accepted = true;
    out->rec.reason = "removed (" + out->rec.reason + ")";
    z.s = out->st;
    std::erase(z.chosen, out->e);
    z.cur_cv = std::move(out->cv);
    z.cur_full = std::move(out->full);
  }
  for (Drop& d : drops) z.sel.records.push_back(std::move(d.rec));
  return out != nullptr;
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

// The final model (select.h) on the selection input `fit_in` (same windows
// as `raw`, which decides the split).
void final_model(const DiagInput& raw, const DiagInput& fit_in, const std::vector<Window>& windows,
                 const SelectOptions& o, const std::vector<Effect>& chosen, Selection& sel) {
  const EffectSet& s = sel.structure;
  const int n = static_cast<int>(windows.size());
  const int n_held = std::clamp(static_cast<int>(std::lround(o.heldout_fraction * n)), 1, n - 1);
  // phase < 0: the last n_held windows; else n_held windows spread evenly,
  // the pattern rotated by `phase` windows.
  auto split = [&](int phase, std::vector<int>& train, std::vector<int>& held) {
    train.clear(), held.clear();
    for (int w = 0; w < n; ++w) {
      const long r = (w + std::max(phase, 0)) % n;
      const bool h = phase < 0 ? w >= n - n_held : (r + 1) * n_held / n > r * n_held / n;
      (h ? held : train).push_back(w);
    }
  };
  const auto acting = acting_samples(raw, windows, s);
  split(-1, sel.train_windows, sel.heldout_windows);
  sel.split = "last";
  bool alt_split = !covers(acting, sel.train_windows, sel.heldout_windows);
  if (!alt_split) {
    ++sel.timing.fits;
    sel.final_fit = fit_effects(fit_in, s, sel.train_windows, sel.heldout_windows, o.fit);
    alt_split = sel.final_fit.rank_deficient;
  }
  if (alt_split) {
    std::vector<int> tr, ho;
    int phase = 0;  // the first rotation that covers, else none
    for (int p = 0; p < n; ++p) {
      split(p, tr, ho);
      if (covers(acting, tr, ho)) {
        phase = p;
        break;
      }
    }
    split(phase, tr, ho);
    ++sel.timing.fits;
    FitSummary f = fit_effects(fit_in, s, tr, ho, o.fit);
    if (!f.rank_deficient || sel.final_fit.params.empty()) {
      sel.final_fit = std::move(f);
      sel.train_windows = tr, sel.heldout_windows = ho, sel.split = "interleaved";
    }
  }
  sel.fitted = true;
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
    EffectSet without = s;
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

}  // namespace

bool SelectOptions::IsValid(std::string* why) const {
  auto fail = [why](std::string msg) {
    if (why) *why = std::move(msg);
    return false;
  };
  std::string w;
  if (!fit.IsValid(&w)) return fail("fit: " + w);
  if (!materiality.IsValid(&w)) return fail("materiality: " + w);
  if (!(pair_above_floor >= 1.0))
    return fail(fmt::format("pair_above_floor = {}; expected >= 1", pair_above_floor));
  if (!(fit.window_s > 0.0))
    return fail(fmt::format("fit.window_s = {}; selection needs windows: expected > 0 s", fit.window_s));
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const Effect e = candidates[i];
    if (static_cast<int>(e) < 0 || static_cast<int>(e) >= kNumEffects)
      return fail(fmt::format("candidates[{}] is not an effect", i));
    if (e == Effect::gyro_bias || e == Effect::gyro_scale)
      return fail(fmt::format("candidate {} acts on the gyro, not on dead reckoning", effect_name(e)));
    if (std::count(candidates.begin(), candidates.end(), e) > 1)
      return fail(fmt::format("candidate {} listed twice", effect_name(e)));
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
      return fail(fmt::format("{} = {}; expected a number in {}{}, {}{}", r.name, r.v, r.lo_in ? "[" : "(",
                              r.lo, r.hi >= 1e300 ? "inf" : fmt::format("{}", r.hi),
                              r.hi_in && r.hi < 1e300 ? "]" : ")"));
  }
  for (std::size_t i = 0; i < zone_boxes.size(); ++i) {
    const ZoneBox& b = zone_boxes[i];
    if (!(std::isfinite(b.x0_m) && std::isfinite(b.x1_m) && std::isfinite(b.y0_m) && std::isfinite(b.y1_m) &&
          b.x0_m < b.x1_m && b.y0_m < b.y1_m))
      return fail(fmt::format("zone_boxes[{}] = [{}, {}] x [{}, {}]; expected finite x0 < x1, y0 < y1", i,
                              b.x0_m, b.x1_m, b.y0_m, b.y1_m));
  }
  return true;
}

double selection_window_s(const DiagInput& in, const SelectOptions& o) {
  if (in.has_ref_heading() || o.min_window_samples <= 0 || in.ref_t_s.size() < 3 || in.odo_t_s.empty())
    return o.fit.window_s;
  std::vector<double> dt;
  for (std::size_t i = 1; i < in.ref_t_s.size(); ++i) dt.push_back(in.ref_t_s[i] - in.ref_t_s[i - 1]);
  std::nth_element(dt.begin(), dt.begin() + static_cast<long>(dt.size() / 2), dt.end());
  const double period = dt[dt.size() / 2];
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
    const std::vector<Window> wf = make_windows(in, window_s), wt = make_windows(si.input, window_s);
    bool same = wt.size() == wf.size();
    for (std::size_t i = 0; same && i < wt.size(); ++i)
      same = std::abs(wt[i].t_begin_s - wf[i].t_begin_s) < 1e-9;
    if (same) {
      si.stride = stride, si.correlated = correlated;
      return si;
    }
  }
  si.input = in;
  return si;
}

Selection select_effects(const DiagInput& in_full, const SelectOptions& o_in) {
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
    sel.timing.total_s = since(t_start);
    return sel;
  }

  const SelectionInput si = selection_input(in_full, o_in);
  const DiagInput* in = &si.input;
  sel.ref_stride = si.stride;
  CrossValidator cv(*in, o.fit, o.folds, si.correlated);
  sel.folds = cv.num_folds();
  Search z{cv, o, sel, EffectSet(), {}, {}, {}, kNaN};
  z.heading = in->has_ref_heading();

  auto t0 = Clock::now();
  z.cur_cv = cv.cross_validate(EffectSet(), {}, o.cv_max_iterations);
  z.cur_full = cv.fit_all(EffectSet(), EffectSet(), o.cv_max_iterations);
  if (!z.cur_cv.ok || !z.cur_full.ok)
    throw std::invalid_argument(fmt::format("track '{}': nominal replay failed: {}", in_full.track_name,
                                            z.cur_cv.error + z.cur_full.error));
  sel.baseline_cv_score = z.cur_cv.score;
  // Rule (e)'s floors against the nominal model's held-out dead reckoning.
  const CrossValidator::Replayed nominal = cv.replayed(z.cur_cv);
  z.floor_m = materiality_floor_m(in_full.ref_sigma_m, nominal.pos_rmse_m, o.materiality);
  if (in_full.has_ref_heading() && std::isfinite(nominal.heading_rmse_rad))
    z.floor_rad = materiality_floor_m(in_full.ref_sigma_rad, nominal.heading_rmse_rad, o.materiality);
  sel.floor_m = z.floor_m;
  sel.floor_rad = z.floor_rad;
  SearchRecord rb;
  rb.phase = "baseline", rb.set = "none", rb.bic = z.cur_full.bic, rb.accepted = true;
  rb.reason = "nominal model";
  fill(rb, z.cur_cv);
  rb.time_s = since(t0);
  sel.records.push_back(rb);

  const std::vector<Effect> cands = candidate_list(in_full, o);
  int step = 1;
  for (; step <= o.max_effects && forward_step(z, step, cands); ++step) {
  }
  for (int round = 1; z.chosen.size() >= 2 && backward_round(z, round); ++round) {
  }
  // Pairs, when what is left stays well above the floor ("Pairs").
  if (o.pairs && static_cast<int>(z.chosen.size()) + 2 <= o.max_effects + 1 &&
      cv.replayed(z.cur_cv).pos_rmse_m > o.pair_above_floor * z.floor_m && pair_step(z, step, cands)) {
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
  sel.final_cv_score = z.cur_cv.score;
  sel.structure = z.s;
  sel.timing.search_s = since(t_start);
  sel.timing.fits = cv.fits();
  if (!z.chosen.empty()) {
    t0 = Clock::now();
    final_model(in_full, *in, windows_full, o, z.chosen, sel);
    sel.timing.final_s = since(t0);
  }
  for (SelectedEffect& e : sel.effects)
    for (const SearchRecord& r : sel.records)
      if (r.phase == "forward" && r.accepted && r.candidate == effect_name(e.effect))
        for (const std::string& name : r.rivals) e.rivals.push_back(effect_from_name(name));
  sel.timing.total_s = since(t_start);
  return sel;
}

}  // namespace odotune::diagnose

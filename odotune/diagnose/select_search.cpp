#include <odotune/diagnose/select_search.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <map>
#include <utility>

#include <fmt/format.h>

#include <odotune/diagnose/materiality.h>
#include <odotune/diagnose/zone_boxes.h>

namespace odotune::diagnose::select_detail {

EffectSet with_effect(const EffectSet& s, Effect e) {
  EffectSet out = s;
  out.enable(e);
  return out;
}

// The materiality rule of the selection: the error `alt` removes from `ref`'s, position and
// (with a reference heading) heading, both measured on their held-out
// predictions replayed as dead reckoning (CrossValidator::replayed), against
// the floors of Search.
Removed removed(CrossValidator& cv, const SetEval& ref, const SetEval& alt) {
  const CrossValidator::Replayed a = cv.replayed(ref), b = cv.replayed(alt);
  return {removed_error_m(a.pos_rmse_m, b.pos_rmse_m),
          std::isfinite(a.heading_rmse_rad) && std::isfinite(b.heading_rmse_rad)
              ? removed_error_m(a.heading_rmse_rad, b.heading_rmse_rad)
              : 0.0};
}

// Material (the materiality rule): "" when the removed position error passes floor_m or
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

// The size, paired-test, BIC and materiality rules of select.h for `alt` to beat `ref`; "" when they
// hold. gain: what alt removes from ref's CV error; floor_m, floor_rad: the
// materiality floors (floor_m 0 = not asked).
std::string verdict(const PairedComparison& p, double delta_bic, const SelectOptions& o, const Removed& gain,
                    double floor_m, double floor_rad) {
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
  r.rel_improvement = p.rel;
  r.gain = p.gain;
  r.windows_changed = p.changed;
  r.windows_improved = p.improved;
  r.p_rank = p.p_rank;
  r.p_t = p.p_t;
  r.p_param = p.p_param;
  r.significant = p.significant;
}

namespace {

constexpr double kMaxCoarseSteps = 32.0;  // radius_step.t coarse grid (profile_step_time)

// The step times profile_step_time searches, [lo, hi], and its coarse step.
struct StepRange {
  double lo = 0.0, hi = 0.0, coarse = 0.0;
};
StepRange step_range(const CrossValidator& cv, const SelectOptions& o) {
  // Earlier, a step is a radius_error: the first step_head_s of the track, or
  // its first window when that is shorter. Not the whole first window: with
  // sparse fixes the windows grow (selection_window_s) and an 80 s first
  // window held a step at 74.2 s, found at 80 s (docs/diagnosis-design.md,
  // "Cases behind the rules").
  const Window& first = cv.windows().front();
  const double head = std::min(o.step_head_s, first.t_end_s - first.t_begin_s);
  const double lo = first.t_begin_s + head;
  // The time the windows cover after lo: gaps between windows (between
  // pooled recordings, or in the reference) hold no step time worth a fit.
  double span = 0.0;
  for (const Window& w : cv.windows()) span += std::max(0.0, w.t_end_s - std::max(w.t_begin_s, lo));
  // At most kMaxCoarseSteps coarse steps: on long tracks the coarse step
  // grows with the track, so the count of fits (each costing the track's
  // length) stays bounded and the search costs linear time.
  const double coarse = std::max(o.step_coarse_s > 0.0 ? o.step_coarse_s : 0.5 * head, span / kMaxCoarseSteps);
  const double hi = cv.windows().back().t_end_s - 0.5 * coarse;
  return {lo, hi, coarse};
}

// The step times fitted so far, with their costs: what a step at t removes
// from the windows' settled costs without one (negative), the current set
// held at its fit.
struct StepProfile {
  CrossValidator& cv;
  const EffectSet& s;
  const std::vector<double>& settled;
  const StepRange& range;
  const SelectOptions& o;
  std::map<double, std::pair<double, EffectSet>> seen;  // t -> (cost, fitted)

  // Fits the times not seen yet, all from `warm`.
  void fit(std::vector<double> ts, const EffectSet& warm) {
    for (double& t : ts) t = std::clamp(t, range.lo, range.hi);
    std::sort(ts.begin(), ts.end());
    ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
    std::erase_if(ts, [&](double t) { return seen.count(t) > 0; });
    std::vector<std::pair<double, EffectSet>> res(ts.size(), {kInf, warm});
#pragma omp parallel for schedule(dynamic, 1) if (ts.size() > 1)
    for (std::size_t i = 0; i < ts.size(); ++i) {
      EffectSet st = with_effect(s, Effect::radius_step);
      st.set(Effect::radius_step, "t", ts[i]);
      // The step's scales alone, the current set held at its fit, on the
      // windows after t (before it the step changes nothing); the cost is
      // what the step removes, negative.
      std::vector<int> after;
      for (const Window& w : cv.windows())
        if (w.t_end_s > ts[i]) after.push_back(w.index);
      try {
        const FitSummary f = cv.screen(start_from(st, warm), Effect::radius_step, after,
                                       o.profile_max_iterations);
        double base = 0.0;
        for (int w : f.fitted_windows) base += settled[static_cast<std::size_t>(w)];
        if (std::isfinite(f.final_cost)) res[i] = {f.final_cost - base, f.effects};
      } catch (const std::exception&) {
      }
    }
    for (std::size_t i = 0; i < ts.size(); ++i) seen[ts[i]] = std::move(res[i]);
  }
  // The time of the lowest cost so far (NaN when none is finite).
  double best_t() const {
    double bt = kNaN, bc = kInf;
    for (const auto& [t, v] : seen)
      if (v.first < bc) {
        bc = v.first;
        bt = t;
      }
    return bt;
  }
};

// Every coarse step of covered time from lo to hi, a gap skipped to the next window.
std::vector<double> coarse_grid(const CrossValidator& cv, const StepRange& r) {
  std::vector<double> grid;
  double t = r.lo;
  for (const Window& w : cv.windows()) {
    t = std::max(t, w.t_begin_s);
    for (; t <= std::min(w.t_end_s, r.hi + 1e-9); t += r.coarse) grid.push_back(t);
  }
  return grid;
}

// radius_step.t by profile search of the screening cost (select.h,
// "Discrete parameters"). The points of one grid level are fitted in
// parallel (OpenMP), each warm-started from the same fit (the current set's,
// then the best point's of the level before), so the result does not depend
// on the thread count.
double profile_step_time(CrossValidator& cv, const EffectSet& s, const EffectSet& s_fitted, double prev_t,
                         const SelectOptions& o) {
  const StepRange range = step_range(cv, o);
  const double lo = range.lo, hi = range.hi, coarse = range.coarse;
  if (!(hi > lo)) return kNaN;
  // Each window's settled cost without a step (a no-op step at any time).
  std::vector<double> settled;
  try {
    settled = cv.settled_costs(
        start_from(with_effect(s, Effect::radius_step), s_fitted).set(Effect::radius_step, "t", lo),
        Effect::radius_step);
  } catch (const std::exception&) {
    return kNaN;
  }
  StepProfile profile{cv, s, settled, range, o, {}};
  if (std::isfinite(prev_t))
    profile.fit({prev_t}, s_fitted);
  else
    profile.fit(coarse_grid(cv, range), s_fitted);
  // Refinement: steps of coarse/5 over +-0.6 coarse (+-0.4 from a previous
  // time), then each level a fifth of the last step (at least step_fine_s)
  // over +- the last step, down to step_fine_s.
  double step = coarse / 5.0, reach = std::isfinite(prev_t) ? 0.4 * coarse : 0.6 * coarse;
  for (;;) {
    const double centre = profile.best_t();
    if (!std::isfinite(centre)) return kNaN;
    const int k = static_cast<int>(std::floor(reach / step + 1e-9));
    std::vector<double> ts;
    for (int i = -k; i <= k; ++i) ts.push_back(centre + i * step);
    profile.fit(ts, profile.seen[centre].second);
    if (step <= o.step_fine_s * (1.0 + 1e-9)) break;
    reach = step;
    step = std::max(o.step_fine_s, step / 5.0);
  }
  return profile.best_t();
}

}  // namespace

// The selection rules (select.h) of a candidate set `cv` (its effects `added`) against the
// current set: fits it on all windows (BIC, into rec), then asks each added
// effect's own parameters to matter (the own-parameters rule). "" when it passes; `full`
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

namespace {

// A candidate of a forward step: its effect, the set with it, its
// cross-validation and its record.
struct Cand {
  Effect e;
  EffectSet st;
  SetEval cv;
  SearchRecord rec;
};

// The candidates not chosen yet, each with its discrete search done
// (radius_step's time, slip_zone's box); `t_cand` gets each one's wall time.
std::vector<Cand> candidates(Search& z, int step, const std::vector<Effect>& cands,
                             std::vector<double>& t_cand) {
  std::vector<Cand> tried;
  for (Effect e : cands) {
    if (std::count(z.chosen.begin(), z.chosen.end(), e)) continue;
    const auto t0 = Clock::now();
    Cand cd{e, with_effect(z.s, e), {}, {}};
    cd.rec.step = step, cd.rec.phase = "forward", cd.rec.candidate = effect_name(e);
    cd.rec.effects = {e};
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
    t_cand.push_back(seconds_since(t0));
    if (e == Effect::radius_step || e == Effect::slip_zone) z.sel.timing.discrete_s += t_cand.back();
    tried.push_back(std::move(cd));
  }
  return tried;
}

// Every candidate's cross-validation at once: the (candidate, fold) fits
// run in parallel (CrossValidator::cross_validate_all); record times are
// the discrete search plus the candidate's share of the batch.
void cross_validate_candidates(Search& z, std::vector<Cand>& tried, std::vector<double>& t_cand) {
  std::vector<EffectSet> sets;
  std::vector<std::size_t> which;
  for (std::size_t i = 0; i < tried.size(); ++i)
    if (tried[i].rec.reason.empty()) {
      sets.push_back(tried[i].st);
      which.push_back(i);
    }
  const auto t_batch = Clock::now();
  std::vector<SetEval> evals = z.cv.cross_validate_all(sets, z.cur_cv.folds, z.o.cv_max_iterations);
  const double share = sets.empty() ? 0.0 : seconds_since(t_batch) / static_cast<double>(sets.size());
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
}

// Candidates by CV score, in the order they are judged (select.h, "Forward
// step"). radius_error goes first unless `rival`, ranked before it, beats it
// by the size and paired-test rules (diagnosis-design.md "Model selection",
// "Candidates"): a radius step is a radius error from a time on (nested: an
// early step fits a constant error's noise, a step at 31 s behind 20 s
// windows' head); without a reference heading a yaw-rate offset bends the
// path as a wheel differential does.
std::vector<Cand*> judging_order(Search& z, std::vector<Cand>& tried) {
  std::vector<Cand*> order;
  for (Cand& cd : tried)
    if (cd.cv.ok) order.push_back(&cd);
  std::stable_sort(order.begin(), order.end(),
                   [](const Cand* a, const Cand* b) { return a->cv.score < b->cv.score; });
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
  return order;
}

}  // namespace

// One forward step; true when a candidate was accepted.
bool forward_step(Search& z, int step, const std::vector<Effect>& cands) {
  std::vector<double> t_cand;  // wall time of each candidate's discrete search
  std::vector<Cand> tried = candidates(z, step, cands, t_cand);
  cross_validate_candidates(z, tried, t_cand);
  // The best few are judged in turn: the first that passes every rule is accepted.
  const std::vector<Cand*> order = judging_order(z, tried);
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
    best->rec.time_s += seconds_since(t0);
    const std::string label = rank == 0 ? "best candidate"
                                        : fmt::format("best candidate that passes (rank {})", rank + 1);
    if (no.empty()) {
      accepted = best->rec.accepted = true;
      best->rec.reason = label + "; improves CV significantly and BIC agrees";
      // Confounded alternatives: candidates the winner does not beat by the size and paired-test rules.
      for (Cand& cd : tried)
        if (cd.cv.ok && &cd != best && !verdict(z.cv.compare(cd.cv, best->cv, z.o.alpha), -1.0, z.o).empty())
          best->rec.rivals.push_back(cd.e);
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

}  // namespace odotune::diagnose::select_detail

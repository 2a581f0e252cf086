#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <odotune/diagnose/select_search.h>

namespace odotune::diagnose::select_detail {

// Without a reference heading (diagnosis-design.md "Model selection", "Candidates"): when the selected set
// holds odometry_bias and not radius_error, the set with radius_error in its
// place is cross-validated, and swapped in unless the selected set beats it
// by the size and paired-test rules and the materiality floor. Logged as a record of
// phase "swap".
void prefer_radius_error(Search& z, int step) {
  const auto has = [&](Effect e) { return std::count(z.chosen.begin(), z.chosen.end(), e) > 0; };
  if (z.heading || !has(Effect::odometry_bias) || has(Effect::radius_error)) return;
  const auto t0 = Clock::now();
  EffectSet st = z.s;
  st.disable(Effect::odometry_bias);
  st.enable(Effect::radius_error);
  SearchRecord rec;
  rec.step = step;
  rec.phase = "swap";
  rec.candidate = "radius_error for odometry_bias";
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
  rec.time_s = seconds_since(t0);
  z.sel.records.push_back(std::move(rec));
}

namespace {

// A swap: `in` in place of the two selected effects `out`.
struct SwapCand {
  Effect in;
  std::vector<Effect> out;
  EffectSet st;
  SearchRecord rec;
};

// Every candidate without a discrete search, not chosen yet, in place of
// each pair of selected effects.
std::vector<SwapCand> swap_candidates(const Search& z, int step, const std::vector<Effect>& cands) {
  const auto chosen = [&](Effect e) { return std::count(z.chosen.begin(), z.chosen.end(), e) > 0; };
  std::vector<SwapCand> tried;
  std::vector<std::vector<Effect>> outs;
  for (std::size_t i = 0; i < z.chosen.size(); ++i) {
    for (std::size_t j = i + 1; j < z.chosen.size(); ++j) outs.push_back({z.chosen[i], z.chosen[j]});
  }
  for (Effect c : cands) {
    if (chosen(c) || c == Effect::radius_step || c == Effect::slip_zone) continue;
    for (const std::vector<Effect>& out : outs) {
      SwapCand cd{c, out, z.s, {}};
      for (Effect e : out) cd.st.disable(e);
      cd.st = with_effect(cd.st, c);
      cd.rec.step = step;
      cd.rec.phase = "swap";
      cd.rec.candidate = fmt::format("{} for {}+{}", effect_name(c), effect_name(out[0]), effect_name(out[1]));
      cd.rec.set = cd.st.to_string();
      tried.push_back(std::move(cd));
    }
  }
  return tried;
}

// Screened by one fit on all windows each (in parallel; a fifth of a
// cross-validation), into `fulls`; returns the one of lowest BIC
// (tried.size() when every fit failed).
std::size_t screen_swaps(Search& z, std::vector<SwapCand>& tried, std::vector<SetEval>& fulls) {
  const auto t0 = Clock::now();
  fulls.assign(tried.size(), SetEval{});
  const auto n_tried = static_cast<long>(tried.size());
#pragma omp parallel for schedule(dynamic, 1) if (n_tried > 1)
  for (long i = 0; i < n_tried; ++i) {
    const auto k = static_cast<std::size_t>(i);
    fulls[k] = z.cv.fit_all(tried[k].st, z.cur_full.fitted, z.o.cv_max_iterations);
  }
  const double share = seconds_since(t0) / static_cast<double>(tried.size());
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
  return best;
}

// Why the best swap `b` (all-window fit `full`) is not made, "" when it is:
// it is cross-validated (into `cv`) unless even its all-window score is
// worse than the selected set's by the size rule's share; the selected set
// must not beat it by the size and materiality rules, and the incoming
// effect's own parameters must matter.
std::string swap_objection(Search& z, SwapCand& b, const SetEval& full, SetEval& cv) {
  std::string no;
  if (!(full.score * (1.0 - z.o.min_rel_improvement) <= z.cur_full.score)) {
    no = fmt::format("on all windows it fits {:.2f} % worse than the selected set",
                     100.0 * (full.score / z.cur_full.score - 1.0));
  } else {
    const auto t1 = Clock::now();
    cv = z.cv.cross_validate_all({b.st}, z.cur_cv.folds, z.o.cv_max_iterations).front();
    b.rec.time_s += seconds_since(t1);
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
  return no;
}

}  // namespace

// Swaps (diagnosis-design.md "Model selection", "Swaps"): one candidate in place of two selected
// effects. Greedy steps accept the effect that predicts best now, and two
// of them can together mimic a third that was never best alone (a speed offset b_v = -0.027 m/s fitted as radius
// error + speed radius beside the true wheel base error). Every candidate
// without a discrete search (not radius_step, not slip_zone) in place of
// each pair of selected effects is fitted on all windows; the lowest BIC is
// cross-validated and swapped in when the selected set does not beat it by
// the size and materiality rules, as the backward pass asks of a removal, and the incoming
// effect's own parameters matter (the own-parameters rule). (One in place of one, tried
// too, changed no case; docs/diagnosis-design.md, "Cases behind the rules".)
// True when a swap was made; logged as records of phase "swap".
bool swap_step(Search& z, int step, const std::vector<Effect>& cands) {
  std::vector<SwapCand> tried = swap_candidates(z, step, cands);
  if (tried.empty()) return false;
  std::vector<SetEval> fulls;
  const std::size_t best = screen_swaps(z, tried, fulls);
  bool swapped = false;
  if (best < tried.size()) {
    SwapCand& b = tried[best];
    for (std::size_t i = 0; i < tried.size(); ++i)
      if (i != best && fulls[i].ok)
        tried[i].rec.reason = fmt::format("not the best swap (BIC on all windows {:.6g} vs {:.6g})",
                                          fulls[i].bic, fulls[best].bic);
    SetEval cv;
    const std::string no = swap_objection(z, b, fulls[best], cv);
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
  for (SwapCand& cd : tried) z.sel.records.push_back(std::move(cd.rec));
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
// best is accepted by the size, paired-test, BIC and materiality rules against the current set, and
// each of its effects must matter by the own-parameters rule. True when a pair was accepted.
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
    cd.rec.step = step;
    cd.rec.phase = "pair";
    cd.rec.candidate = fmt::format("{}+{}", effect_name(pr.first), effect_name(pr.second));
    cd.rec.effects = {pr.first, pr.second};
    cd.rec.set = cd.st.to_string();
    sets.push_back(cd.st);
    tried.push_back(std::move(cd));
  }
  // All pairs' (pair, fold) fits in one parallel batch, as a forward step's.
  const auto t_batch = Clock::now();
  std::vector<SetEval> evals = z.cv.cross_validate_all(sets, z.cur_cv.folds, z.o.cv_max_iterations);
  const double share = sets.empty() ? 0.0 : seconds_since(t_batch) / static_cast<double>(sets.size());
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
    best->rec.time_s += seconds_since(t0);
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

namespace {

// A removal of the backward pass: the selected set without `e`.
struct Drop {
  Effect e;
  EffectSet st;
  SetEval cv, full;
  SearchRecord rec;
  bool removable = false;
};

// Whether d's effect can go (d.removable, with its reason in d.rec), its
// removal cross-validated and fitted on all windows.
void judge_drop(Search& z, Drop& d) {
  const PairedComparison p = z.cv.compare(d.cv, z.cur_cv, z.o.alpha);  // keeping e vs dropping it
  fill(d.rec, p);
  d.rec.bic = d.full.bic;
  d.rec.delta_bic = z.cur_full.bic - d.full.bic;
  // Redundancy by the size rule only: once another effect changes every
  // window, an intermittent effect's paired test has little power left.
  // Or by the materiality rule: what it gains is immaterial.
  const std::string why = immaterial(removed(z.cv, d.cv, z.cur_cv), z.floor_m, z.floor_rad);
  const bool material = why.empty();
  d.removable = !(p.rel >= z.o.min_rel_improvement && p.gain >= z.o.min_gain) || !material;
  d.rec.reason = !material     ? "removable: " + why
                 : d.removable ? fmt::format("removable: without it CV is only {:.2f} % worse", 100.0 * p.rel)
                               : "kept: it is needed";
  // Rule (d) again for an effect whose no-op is not its absence
  // (noop_differs_from_absence; actuator_lag replays the commands):
  // accepted within a pair, it may be left alone by the pair's other
  // effect's removal, and then its own parameters must still matter
  // (a null track's 360-cpr encoders
  // lost to the commands; actuator_lag + time_offset passed as a pair,
  // time_offset was dropped, tau = 0.14 ms stayed).
  if (!d.removable && noop_differs_from_absence(d.e)) {
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
}

}  // namespace

// One backward round; true when an effect was removed.
bool backward_round(Search& z, int round) {
  std::vector<Drop> drops;
  const auto t0 = Clock::now();
  std::vector<EffectSet> sets;
  for (Effect e : z.chosen) {
    Drop d{e, z.s, {}, {}, {}, false};
    d.st.disable(e);
    d.rec.step = round, d.rec.phase = "backward", d.rec.candidate = effect_name(e);
    d.rec.effects = {e};
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
  const double share = drops.empty() ? 0.0 : seconds_since(t0) / static_cast<double>(drops.size());
  for (Drop& d : drops) {
    fill(d.rec, d.cv);
    if (d.cv.ok && d.full.ok)
      judge_drop(z, d);
    else
      d.rec.reason = "fit without it failed: " + d.cv.error + d.full.error;
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

// Look-alikes (diagnosis-design.md "Model selection", "Look-alikes"): the chosen effects among a time
// offset, a first-order actuator lag and acceleration-driven longitudinal
// slip, against every other choice of those three with no more effects.
bool look_alike_step(Search& z, int step) {
  std::vector<Effect> have;
  for (Effect e : kLagLookAlikes)
    if (std::count(z.chosen.begin(), z.chosen.end(), e)) have.push_back(e);
  if (have.empty()) return false;
  struct Alt {
    std::vector<Effect> effects;
    EffectSet st;
    SearchRecord rec;
  };
  std::vector<Alt> alts;
  for (unsigned mask = 1; mask < 8; ++mask) {
    std::vector<Effect> a;
    for (unsigned i = 0; i < 3; ++i)
      if (mask & (1u << i)) a.push_back(kLagLookAlikes[i]);
    if (a == have || a.size() > have.size()) continue;
    Alt alt{a, z.s, {}};
    for (Effect e : have) alt.st.disable(e);
    for (Effect e : a) alt.st = with_effect(alt.st, e);
    std::string names;
    for (Effect e : a) names += (names.empty() ? "" : "+") + std::string(effect_name(e));
    alt.rec.step = step;
    alt.rec.phase = "look-alike";
    alt.rec.candidate = names;
    alt.rec.set = alt.st.to_string();
    alts.push_back(std::move(alt));
  }
  std::vector<EffectSet> sets;
  for (const Alt& a : alts) sets.push_back(a.st);
  const auto t0 = Clock::now();
  std::vector<SetEval> evals = z.cv.cross_validate_all(sets, z.cur_cv.folds, z.o.cv_max_iterations);
  const double share = seconds_since(t0) / static_cast<double>(std::max<std::size_t>(alts.size(), 1));
  // An alternative predicts alike when the chosen effects do not beat it by
  // the size and paired-test rules; of those, the one with the fewest effects (then the
  // best CV) replaces them when it has fewer.
  std::size_t best = alts.size();
  for (std::size_t i = 0; i < alts.size(); ++i) {
    Alt& a = alts[i];
    a.rec.time_s = share;
    if (!evals[i].ok) {
      a.rec.reason = "fit failed: " + evals[i].error;
      continue;
    }
    fill(a.rec, evals[i]);
    fill(a.rec, z.cv.compare(evals[i], z.cur_cv, z.o.alpha));
    const bool alike = !verdict(z.cv.compare(evals[i], z.cur_cv, z.o.alpha), -1.0, z.o).empty();
    a.rec.reason = alike ? "predicts alike: the chosen effects do not beat it"
                         : "the chosen effects predict better";
    if (!alike) continue;
    for (Effect e : a.effects)
      if (!std::count(z.look_alikes.begin(), z.look_alikes.end(), e)) z.look_alikes.push_back(e);
    if (a.effects.size() < have.size() &&
        (best == alts.size() || a.effects.size() < alts[best].effects.size() ||
         (a.effects.size() == alts[best].effects.size() && evals[i].score < evals[best].score)))
      best = i;
  }
  bool replaced = false;
  if (best < alts.size()) {
    Alt& b = alts[best];
    SetEval full = z.cv.fit_all(b.st, z.cur_full.fitted, z.o.cv_max_iterations);
    if (full.ok) {
      b.rec.accepted = true;
      b.rec.reason = "predicts alike with fewer effects: the simpler reading replaces the chosen ones";
      for (Effect e : have) {
        z.chosen.erase(std::remove(z.chosen.begin(), z.chosen.end(), e), z.chosen.end());
        if (!std::count(z.look_alikes.begin(), z.look_alikes.end(), e)) z.look_alikes.push_back(e);
      }
      for (Effect e : b.effects) z.chosen.push_back(e);
      z.s = b.st;
      z.cur_cv = std::move(evals[best]);
      z.cur_full = std::move(full);
      replaced = true;
    }
  }
  for (Alt& a : alts) z.sel.records.push_back(std::move(a.rec));
  return replaced;
}

}  // namespace odotune::diagnose::select_detail

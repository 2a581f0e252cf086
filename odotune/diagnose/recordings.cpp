#include <odotune/diagnose/recordings.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/diagnose/fit.h>
#include <odotune/diagnose/materiality.h>
#include <odotune/diagnose/paired_test.h>
#include <odotune/diagnose/select.h>
#include <odotune/diagnose/sensor_checks.h>
#include <odotune/diagnose/term_search.h>
#include <odotune/diagnose/window_replay.h>

namespace odotune::diagnose {
namespace {

bool same(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max({1.0, std::abs(a), std::abs(b)}); }

template <class V>
void append_shifted(V& out, const V& in, double shift) {
  for (double v : in) out.push_back(v + shift);
}

// The wheel effects the pooled diagnosis chose, with their fitted values.
EffectSet wheel_model(const Diagnosis& d) {
  return d.selection.fitted ? d.selection.final_fit.effects : EffectSet();
}

std::string short_name(const std::string& slot) { return slot.substr(slot.find('.') + 1); }

// A term model found on the fitted recordings (the unexplained finding's
// `model`), replayed on the held-out recordings: proven only when it lowers
// their pooled error by their materiality floor; else said so.
struct TermsElsewhere {
  std::vector<Finding> findings;         // with each term model's other_recordings and proven
  std::vector<std::string> consistency;  // one line per term model
};

TermsElsewhere prove_terms_elsewhere(std::vector<Finding> findings, const EffectSet& wheel, double ws,
                                     const std::vector<DiagInput>& heldout, const DiagnoseOptions& o) {
  TermsElsewhere out;
  for (Finding& f : findings) {
    if (!f.model) continue;
    std::vector<sim::ModelTerm> terms;
    for (const FoundTerm& t : f.model->terms) terms.push_back(t.term);
    PooledError before, after, sigma;
    for (const DiagInput& in : heldout) {
      const TermScore t = replay_terms(in, wheel, terms, ws, o.terms);
      before.add(t.before_pos_rmse_m, 0.0, t.samples);
      after.add(t.after_pos_rmse_m, 0.0, t.samples);
      sigma.add(in.ref_sigma_m, 0.0, t.samples);
    }
    if (before.empty()) continue;
    const TermScore pooled{before.pos_rmse_m(), after.pos_rmse_m(), static_cast<std::size_t>(before.n)};
    const double floor = materiality_floor_m(sigma.pos_rmse_m(), pooled.before_pos_rmse_m,
                                             o.select.materiality);
    f.model->other_recordings = pooled;
    f.model->proven = is_material(pooled.before_pos_rmse_m, pooled.after_pos_rmse_m, floor);
    out.consistency.push_back(
        fmt::format("the terms {} {} on the held-out recordings: {:.1f} → {:.1f} mm (floor {:.1f} mm)",
                    f.model->formula, f.model->proven ? "hold" : "fit the fitted recordings only, not proven",
                    1e3 * pooled.before_pos_rmse_m, 1e3 * pooled.after_pos_rmse_m, 1e3 * floor));
  }
  out.findings = std::move(findings);
  return out;
}

// The windows of `after` against `before` on one recording, for the paired
// test (paired_test.h): against the raw reference, heading when it has one.
void add_window_pairs(const DiagInput& in, double ws, const ReplayResult& before, const ReplayResult& after,
                      std::vector<WindowPair>& out) {
  const bool heading = in.has_ref_heading();
  const PoseSamples b{before.pred_x_m, before.pred_y_m, before.pred_theta_rad},
      a{after.pred_x_m, after.pred_y_m, after.pred_theta_rad}, ref = reference_poses(in);
  for (const Window& w : make_windows(in, ws)) {
    const double n = static_cast<double>(w.ref_end - w.ref_begin);
    out.push_back({normalised_sq_distance(in, w, b, ref, heading),
                   normalised_sq_distance(in, w, a, ref, heading), normalised_sq_distance(in, w, a, b, heading),
                   n * (heading ? 3.0 : 2.0)});
  }
}

std::vector<ReplayResult> replay_each(const std::vector<DiagInput>& ins, const EffectSet& set, double ws) {
  std::vector<ReplayResult> out;
  for (const DiagInput& in : ins) out.push_back(replay(in, set, ws));
  return out;
}

PooledError pool(const std::vector<ReplayResult>& r) {
  PooledError p;
  for (const ReplayResult& x : r) p.add(x);
  return p;
}

// The held-out recordings' test of `after` against `before` (recordings.h):
// material against their own floor, in position or in heading, and
// consistent over their windows. The floors are against `nominal`'s error.
HeldoutTest heldout_test(const std::vector<ReplayResult>& before, const std::vector<ReplayResult>& after,
                         const std::vector<ReplayResult>& nominal, const std::vector<DiagInput>& heldout,
                         double ws, const DiagnoseOptions& o) {
  PooledError b = pool(before), a = pool(after), n = pool(nominal), nominal_sigma;
  for (std::size_t k = 0; k < heldout.size(); ++k)
    for (const WindowError& w : before[k].windows)
      nominal_sigma.add(heldout[k].ref_sigma_m, heldout[k].ref_sigma_rad, w.n_ref);
  HeldoutTest t;
  for (const ReplayResult& r : before) t.windows += static_cast<int>(r.windows.size());
  t.error = {b.pos_rmse_m(), a.pos_rmse_m()};
  std::vector<WindowPair> pairs;
  for (std::size_t k = 0; k < heldout.size(); ++k) add_window_pairs(heldout[k], ws, before[k], after[k], pairs);
  t.paired = paired_windows(pairs, 1.0, o.heldout_alpha);
  const auto& m = o.select.materiality;
  t.floor_m = materiality_floor_m(nominal_sigma.pos_rmse_m(), n.pos_rmse_m(), m);
  t.material = is_material(b.pos_rmse_m(), a.pos_rmse_m(), t.floor_m);
  if (heldout.front().has_ref_heading()) {
    const double floor_rad = materiality_floor_m(nominal_sigma.heading_rmse_rad(), n.heading_rmse_rad(), m);
    t.material = t.material ||
                 (floor_rad > 0.0 && is_material(b.heading_rmse_rad(), a.heading_rmse_rad(), floor_rad));
  }
  t.proven = t.material && t.paired.significant;
  return t;
}

// Held-out recordings confirm each wheel finding (recordings.h): those they
// do not are dropped from the findings, the wheel model and the chosen model
// and listed in not_confirmed; every kept finding's `heldout` numbers and
// test are then against the reduced model.
struct Confirmed {
  std::vector<Finding> findings;
  EffectSet wheel, model;  // the pooled wheel model and chosen model, reduced
  std::vector<std::string> not_confirmed;
};

Confirmed confirm_on_heldout(const Diagnosis& d, const std::vector<DiagInput>& heldout,
                             const DiagnoseOptions& o) {
  Confirmed c{.findings = d.findings, .wheel = wheel_model(d), .model = d.model, .not_confirmed = {}};
  const double ws = d.window_s;
  const std::vector<ReplayResult> nominal = replay_each(heldout, EffectSet(), ws);
  const auto test_each = [&](bool drop) {
    const std::vector<ReplayResult> with = replay_each(heldout, c.wheel, ws);
    std::vector<Effect> dropped;
    for (Finding& f : c.findings) {
      if (!f.is_wheel_effect()) continue;
      EffectSet without = c.wheel;
      without.disable(f.effect());
      const HeldoutTest t = heldout_test(replay_each(heldout, without, ws), with, nominal, heldout, ws, o);
      f.heldout = t.error;
      f.heldout_test = t;
      if (drop && !t.material) {
        dropped.push_back(f.effect());
        c.not_confirmed.push_back(fmt::format(
            "{}: fits the fitted recordings; on the held-out recordings it removes less than their floor "
            "({:.1f} → {:.1f} mm, floor {:.1f} mm; {})",
            f.spec(), 1e3 * t.error.before_pos_rmse_m, 1e3 * t.error.after_pos_rmse_m, 1e3 * t.floor_m,
            describe(t)));
      }
    }
    for (Effect e : dropped) {
      c.wheel.disable(e);
      c.model.disable(e);
    }
    std::erase_if(c.findings, [&](const Finding& f) { return f.is_wheel_effect() && !c.wheel.on(f.effect()); });
    return !dropped.empty();
  };
  if (test_each(true)) test_each(false);
  return c;
}

// The options of the pooled diagnosis: the selection leaves one recording out
// at a time (an effect is chosen because it predicts a recording it was not
// fitted on).
DiagnoseOptions pooled_options(const DiagnoseOptions& o, const std::vector<DiagInput>& fit,
                               const std::vector<double>& shifts) {
  DiagnoseOptions pooled = o;
  pooled.select.recording_starts_s.clear();
  if (fit.size() >= 2)
    for (std::size_t k = 0; k < fit.size(); ++k)
      pooled.select.recording_starts_s.push_back(fit[k].odo_t_s.front() + shifts[k]);
  return pooled;
}

// What evaluate_recording needs besides the recording: the pooled model,
// its window, and the options of each recording's refit.
struct RecordingEval {
  const EffectSet& wheel;
  double ws;
  const DiagnoseOptions& o;
  const SelectOptions& so;
  const FitOptions& fo;
};

// One recording evaluated: its result, and its replays with the nominal and
// the pooled model when both could be made.
struct EvaluatedRecording {
  RecordingResult result;
  bool replayed = false;
  ReplayResult nominal, modelled;
};

// One recording: its sensor check, nominal vs the pooled model and the refit
// alone (on its selection input, as the pooled final fit, from the pooled
// values), into `r` (which names the recording). A failure goes to its note.
EvaluatedRecording evaluate_recording(const DiagInput& in, const RecordingEval& e, RecordingResult r) {
  EvaluatedRecording out;
  try {
    const OdometryCheck oc = check_sensors(in, e.o.sensors).odometry;
    if (oc.available) {
      r.speed_ratio = oc.speed_ratio.value;
      r.yaw_ratio = oc.yaw_ratio.value;
      // odo(t) ≈ ref(t − lag): the motion shows up -lag after the odometry.
      const LagEstimate& lag = oc.command_delay.available ? oc.command_delay : oc.odometry_late;
      if (lag.available) r.motion_late_s = oc.command_delay.available ? lag.lag_s : -lag.lag_s;
    }
    out.nominal = replay(in, EffectSet(), e.ws);
    out.modelled = replay(in, e.wheel, e.ws);
    out.replayed = true;
    r.error = {out.nominal.pos_rmse_m, out.modelled.pos_rmse_m};
    r.floor_m = materiality_floor_m(in.ref_sigma_m, out.nominal.pos_rmse_m, e.o.select.materiality);
    r.helped = is_material(out.nominal.pos_rmse_m, out.modelled.pos_rmse_m, r.floor_m);
    if (!e.wheel.empty()) {
      // From the pooled values: a parameter started at its no-op bound can stay there.
      const FitSummary f = fit_effects(selection_input(in, e.so).input, e.wheel, {}, {}, e.fo);
      for (const FitParam& p : f.params)
        if (p.fitted) {
          r.refit.push_back({p.name, p.value});
          r.refit_stderr.push_back({p.name, p.std_error});
        }
    }
  } catch (const std::exception& ex) {
    r.note = ex.what();
  }
  out.result = std::move(r);
  return out;
}

// Per refitted parameter: whether the recordings' refits agree, one line each.
std::vector<std::string> refit_agreement(const std::vector<RecordingResult>& recordings,
                                         const EffectSet& wheel) {
  std::vector<std::string> lines;
  const auto& names = recordings.front().refit;
  const std::vector<ParamSlot> layout = param_layout(wheel);  // the refits' names are among its slots
  for (std::size_t i = 0; i < names.size(); ++i) {
    std::vector<double> v;
    std::string list;
    double se = 0.0;
    for (const RecordingResult& r : recordings)
      if (i < r.refit.size()) {
        v.push_back(r.refit[i].value);
        se = std::max(se, r.refit_stderr[i].value);
        list += fmt::format("{}{:.5g}", list.empty() ? "" : ", ", r.refit[i].value);
      }
    if (v.size() < 2) continue;
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    const auto slot = std::find_if(layout.begin(), layout.end(),
                                   [&](const ParamSlot& p) { return p.name == names[i].name; });
    const double pooled = wheel.params(slot->effect)[static_cast<std::size_t>(slot->index)];
    const double noop_dist = std::abs(pooled - (short_name(names[i].name).rfind("scale", 0) == 0 ? 1.0 : 0.0));
    // Holds when the recordings agree within half the effect's size (or within 4 standard errors).
    const bool holds = (*hi - *lo) <= std::max(0.5 * noop_dist, 4.0 * se);
    lines.push_back(fmt::format("{}: {} alone on each recording ({}), pooled {:.5g}: {}", names[i].name,
                                holds ? "agrees" : "differs", list, pooled,
                                holds ? "holds across recordings" : "does not hold across recordings"));
  }
  return lines;
}

// What holds across recordings: each recording's error with the pooled
// model, then whether the refits agree; one line each.
std::vector<std::string> consistency(const std::vector<RecordingResult>& recordings, const EffectSet& wheel) {
  std::vector<std::string> lines;
  for (const RecordingResult& r : recordings) {
    if (!r.note.empty()) {
      lines.push_back(fmt::format("{}: not evaluated ({})", r.track, r.note));
      continue;
    }
    if (wheel.empty()) continue;
    lines.push_back(fmt::format(
        "{} ({}): the pooled model {} its position error {:.1f} → {:.1f} mm (floor {:.1f} mm)", r.track,
        r.heldout ? "held out" : "fitted", r.helped ? "cuts" : "does not materially change",
        1e3 * r.error.before_pos_rmse_m, 1e3 * r.error.after_pos_rmse_m, 1e3 * r.floor_m));
  }
  if (!wheel.empty() && !recordings.empty()) {
    std::vector<std::string> agree = refit_agreement(recordings, wheel);
    lines.insert(lines.end(), agree.begin(), agree.end());
  }
  return lines;
}

// Per recording (fit recordings first): nominal vs the pooled model, and the
// refit alone, recordings in parallel. shifts: the fit recordings' pooled
// time offsets.
std::vector<EvaluatedRecording> evaluate_recordings(const std::vector<DiagInput>& all, std::size_t n_fit,
                                                    const std::vector<double>& shifts, const EffectSet& wheel,
                                                    double ws, const DiagnoseOptions& o) {
  FitOptions fo = o.select.fit;
  fo.window_s = ws;
  SelectOptions so = o.select;
  so.fit.window_s = ws;
  so.min_window_samples = 0.0;  // the pooled windows' length, not one of its own
  const RecordingEval eval{wheel, ws, o, so, fo};
  std::vector<EvaluatedRecording> out(all.size());
#pragma omp parallel for schedule(dynamic, 1) if (all.size() > 1)
  for (std::size_t k = 0; k < all.size(); ++k) {
    const DiagInput& in = all[k];
    RecordingResult r;
    r.track = in.track_name;
    r.heldout = k >= n_fit;
    r.duration_s = in.odo_t_s.back() - in.odo_t_s.front();
    r.ref_samples = in.ref_t_s.size();
    r.ref_sigma_m = in.ref_sigma_m;
    r.pooled_time_offset_s = k < shifts.size() ? shifts[k] : std::nan("");
    out[k] = evaluate_recording(in, eval, std::move(r));
  }
  return out;
}

// The held-out recordings' test of the pooled model against the nominal one
// (file comment), over those whose replays could be made; nullopt for none.
std::optional<HeldoutTest> prove_on_heldout(const std::vector<DiagInput>& all, std::size_t n_fit,
                                            const std::vector<EvaluatedRecording>& evaluated, double ws,
                                            const DiagnoseOptions& o) {
  std::vector<ReplayResult> held_nominal, held_model;
  std::vector<DiagInput> replayed_heldout;
  for (std::size_t k = n_fit; k < all.size(); ++k)
    if (evaluated[k].replayed) {
      held_nominal.push_back(evaluated[k].nominal);
      held_model.push_back(evaluated[k].modelled);
      replayed_heldout.push_back(all[k]);
    }
  if (replayed_heldout.empty()) return std::nullopt;
  return heldout_test(held_nominal, held_model, held_nominal, replayed_heldout, ws, o);
}

}  // namespace

std::string describe(const HeldoutTest& t) {
  const PairedComparison& c = t.paired;
  return fmt::format("paired test over {} windows, {} informative, {} better: rank p = {:.2g}, t p = {:.2g}, "
                     "Stouffer p = {:.2g}",
                     t.windows, c.changed, c.improved, c.p_rank, c.p_t, c.p_param);
}

void check_one_robot(const std::vector<DiagInput>& parts) {
  if (parts.empty()) return;
  const DiagInput& a = parts.front();
  for (const DiagInput& p : parts) {
    const auto bad = [&](const std::string& what) {
      throw std::invalid_argument(fmt::format("recording '{}' is not of the robot of '{}': {}", p.track_name,
                                              a.track_name, what));
    };
    if (p.odometry != a.odometry) bad("another kind of odometry");
    if (!same(p.radius_l_m, a.radius_l_m) || !same(p.radius_r_m, a.radius_r_m) ||
        !same(p.wheel_base_m, a.wheel_base_m))
      bad(fmt::format("nominal radii {} m, {} m and base {} m, expected {} m, {} m and {} m", p.radius_l_m,
                      p.radius_r_m, p.wheel_base_m, a.radius_l_m, a.radius_r_m, a.wheel_base_m));
    if (p.has_ref_heading() != a.has_ref_heading()) bad("reference heading on one and not on the other");
    if (p.cmd_v_mps.empty() != a.cmd_v_mps.empty()) bad("commands on one and not on the other");
  }
}

DiagInput concatenate(const std::vector<DiagInput>& parts, double gap_s, std::vector<double>* shifts) {
  if (parts.empty()) throw std::invalid_argument("concatenate: no recording");
  if (shifts) shifts->assign(parts.size(), 0.0);
  if (parts.size() == 1) return parts.front();
  check_one_robot(parts);
  const DiagInput& a = parts.front();
  double sigma = a.ref_sigma_m;  // the pooled sigma: that of the recording with the most samples
  std::size_t most = 0;
  for (const DiagInput& p : parts)
    if (p.ref_t_s.size() > most) {
      most = p.ref_t_s.size();
      sigma = p.ref_sigma_m;
    }
  DiagInput c;
  c.track_name = a.track_name;
  for (std::size_t k = 1; k < parts.size(); ++k) c.track_name += " + " + parts[k].track_name;
  c.radius_l_m = a.radius_l_m;
  c.radius_r_m = a.radius_r_m;
  c.wheel_base_m = a.wheel_base_m;
  c.odometry = a.odometry;
  c.velocity_source = a.velocity_source;
  c.reference = a.reference;
  c.ref_sigma_m = sigma;
  c.ref_sigma_rad = a.ref_sigma_rad;
  bool weighted = false;
  for (const DiagInput& p : parts) weighted = weighted || !p.ref_w.empty() || !same(p.ref_sigma_m, sigma);
  double end = 0.0, phi_l = 0.0, phi_r = 0.0;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const DiagInput& p = parts[k];
    const double start = std::min(p.odo_t_s.front(), p.ref_t_s.empty() ? p.odo_t_s.front() : p.ref_t_s.front());
    const double shift = k == 0 ? 0.0 : end + gap_s - start;
    if (shifts) (*shifts)[k] = shift;
    append_shifted(c.odo_t_s, p.odo_t_s, shift);
    if (!p.phi_l_rad.empty()) {
      const double l0 = k == 0 ? 0.0 : phi_l - p.phi_l_rad.front(),
                   r0 = k == 0 ? 0.0 : phi_r - p.phi_r_rad.front();
      append_shifted(c.phi_l_rad, p.phi_l_rad, l0);
      append_shifted(c.phi_r_rad, p.phi_r_rad, r0);
      phi_l = c.phi_l_rad.back();
      phi_r = c.phi_r_rad.back();
    }
    c.v_mps.insert(c.v_mps.end(), p.v_mps.begin(), p.v_mps.end());
    c.w_radps.insert(c.w_radps.end(), p.w_radps.begin(), p.w_radps.end());
    c.cmd_v_mps.insert(c.cmd_v_mps.end(), p.cmd_v_mps.begin(), p.cmd_v_mps.end());
    c.cmd_w_radps.insert(c.cmd_w_radps.end(), p.cmd_w_radps.begin(), p.cmd_w_radps.end());
    append_shifted(c.gyro_t_s, p.gyro_t_s, shift);
    c.gyro_z_radps.insert(c.gyro_z_radps.end(), p.gyro_z_radps.begin(), p.gyro_z_radps.end());
    append_shifted(c.ref_t_s, p.ref_t_s, shift);
    c.ref_x_m.insert(c.ref_x_m.end(), p.ref_x_m.begin(), p.ref_x_m.end());
    c.ref_y_m.insert(c.ref_y_m.end(), p.ref_y_m.begin(), p.ref_y_m.end());
    c.ref_theta_rad.insert(c.ref_theta_rad.end(), p.ref_theta_rad.begin(), p.ref_theta_rad.end());
    if (weighted) {
      const double scale = (sigma / p.ref_sigma_m) * (sigma / p.ref_sigma_m);
      for (std::size_t i = 0; i < p.ref_t_s.size(); ++i) c.ref_w.push_back(scale * p.ref_weight(i));
    }
    c.ref_gt_samples += p.ref_gt_samples;
    c.ref_fix_samples += p.ref_fix_samples;
    end = std::max(c.odo_t_s.back(), c.ref_t_s.empty() ? c.odo_t_s.back() : c.ref_t_s.back());
  }
  return c;
}

DiagInput pool_recordings(const std::vector<DiagInput>& fit, std::vector<double>* shifts) {
  // A gap longer than any window the selection may choose (at most a third of the pooled span).
  double span = 0.0;
  for (const DiagInput& p : fit) span += p.odo_t_s.back() - p.odo_t_s.front();
  return concatenate(fit, std::max(1000.0, span), shifts);
}

PooledDiagnosis diagnose_recordings(const std::vector<DiagInput>& fit, const std::vector<DiagInput>& heldout,
                                    const DiagnoseOptions& o) {
  if (fit.empty()) throw std::invalid_argument("diagnose_recordings: no recording to fit on");
  std::vector<DiagInput> all = fit;
  all.insert(all.end(), heldout.begin(), heldout.end());
  check_one_robot(all);
  std::vector<double> shifts;
  DiagInput input = pool_recordings(fit, &shifts);
  Diagnosis d = diagnose(input, pooled_options(o, fit, shifts));
  const double ws = d.window_s;
  const bool with_heldout = !heldout.empty();
  Confirmed confirmed =
      with_heldout
          ? confirm_on_heldout(d, heldout, o)
          : Confirmed{.findings = d.findings, .wheel = wheel_model(d), .model = d.model, .not_confirmed = {}};
  const EffectSet& wheel = confirmed.wheel;
  std::vector<EvaluatedRecording> evaluated = evaluate_recordings(all, fit.size(), shifts, wheel, ws, o);
  std::optional<HeldoutTest> test;
  TermsElsewhere terms{.findings = std::move(confirmed.findings), .consistency = {}};
  if (with_heldout) {
    test = prove_on_heldout(all, fit.size(), evaluated, ws, o);
    terms = prove_terms_elsewhere(std::move(terms.findings), wheel, ws, heldout, o);
  }
  std::vector<RecordingResult> recordings;
  for (EvaluatedRecording& e : evaluated) recordings.push_back(std::move(e.result));
  std::vector<std::string> lines = std::move(terms.consistency);
  for (std::string& line : consistency(recordings, wheel)) lines.push_back(std::move(line));

  // The pooled diagnosis as the held-out recordings leave it (file comment).
  if (with_heldout &&
      !confirmed.not_confirmed.empty()) {  // the fitted recordings' error with the model as reported
    const ReplayResult fin = replay(input, wheel, ws);
    d.final_pos_rmse_m = fin.pos_rmse_m;
    d.final_heading_rmse_rad = fin.heading_rmse_rad;
  }
  if (test) d.heldout = test->error;
  d.findings = std::move(terms.findings);
  d.model = std::move(confirmed.model);
  d.not_confirmed = std::move(confirmed.not_confirmed);
  return {.input = std::move(input),
          .pooled = std::move(d),
          .heldout_recordings = with_heldout,
          .heldout_test = test.value_or(HeldoutTest{}),
          .recordings = std::move(recordings),
          .consistency = std::move(lines)};
}

}  // namespace odotune::diagnose

#include <odotune/diagnose/diagnosis_summary.h>

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include <odotune/sim/effects.h>
#include <odotune/sim/model_terms.h>

namespace odotune::diagnose {
namespace {

using namespace odotune::diagnose;

// The effect's name in words: "lateral_skid" -> "lateral skid".
std::string words(std::string_view effect) {
  std::string s(effect);
  std::replace(s.begin(), s.end(), '_', ' ');
  return s;
}

std::string unit_of(std::string_view effect, const std::string& param) {
  const sim::EffectInfo* e = sim::find_effect(effect);
  if (!e) return "";
  const sim::EffectParamInfo* p = sim::find_param(*e, param);
  if (!p || p->unit == "1") return "";
  return " " + std::string(p->unit);
}

// Value and uncertainty with the value's last digit at the uncertainty's
// second significant digit (at most 8 decimals).
std::string plus_minus(double value, double err) {
  if (!std::isfinite(err) || err <= 0.0) return fmt::format("{:.6g}", value);
  const int digits = std::clamp(1 - static_cast<int>(std::floor(std::log10(err))), 0, 8);
  return fmt::format("{:.{}f} ± {:.{}f}", value, digits, err, digits);
}

double pct_change(const BeforeAfter& s) {
  return 100.0 * (s.after_pos_rmse_m - s.before_pos_rmse_m) / s.before_pos_rmse_m;
}

std::string metres(double m) { return fmt::format("{:.3f} m", m); }

std::string spans(const std::vector<TimeSegment>& segs, std::size_t max_shown = 4) {
  std::string s;
  for (std::size_t i = 0; i < segs.size() && i < max_shown; ++i)
    s += fmt::format("{}{:.1f}–{:.1f} s", i == 0 ? "" : ", ", segs[i].t0_s, segs[i].t1_s);
  if (segs.size() > max_shown) s += fmt::format(" and {} more", segs.size() - max_shown);
  return s;
}

// A finding on body-velocity odometry in the odometry's own terms; "" for effects without such a reading. `src` is "command" or
// "velocity odometry". Kinematics as effect_model.h applies them to v, w:
// radius_error scales both wheels' rim speeds (v, w gain (s_l + s_r)/2),
// wheel_base_error divides w by its scale, time_offset dt < 0 means the
// motion shows up |dt| after the odometry's stamp.
std::string velocity_terms(const Finding& f, const std::string& src) {
  if (f.is(Effect::radius_error)) {
    const double g = 0.5 * (f.param("scale_l") + f.param("scale_r"));
    return fmt::format("speed and turn-rate gain {:.4f}: the robot moves {:.2f} % {} than the {} says", g,
                       100.0 * std::abs(g - 1.0), g >= 1.0 ? "more" : "less", src);
  }
  if (f.is(Effect::wheel_base_error))
    return fmt::format("turn-rate gain {:.4f}: the robot turns {:.2f} % {} than the {} says",
                       1.0 / f.param("scale"), 100.0 * std::abs(1.0 / f.param("scale") - 1.0),
                       f.param("scale") <= 1.0 ? "more" : "less", src);
  if (f.is(Effect::time_offset)) {
    const double dt = f.param("dt");
    return dt <= 0.0 ? fmt::format("motion lags the {} by {:.3f} s", src, -dt)
                     : fmt::format("the {} lags the motion by {:.3f} s", src, dt);
  }
  if (f.is(Effect::actuator_lag))
    return fmt::format("motion follows the {} through a first-order lag of {:.3f} s", src, f.param("tau"));
  if (f.is(Effect::odometry_bias))
    return fmt::format(
        "the {} reads {:+.4f} m/s and {:+.4f} rad/s at rest: a robot standing still seems to move", src,
        f.param("b_v"), f.param("b_w"));
  if (f.is(Effect::speed_radius))
    return fmt::format("speed gain grows with speed: 1 + {:.3g}·u² (u the wheel rim speed, m/s)", f.param("c"));
  return "";
}

}  // namespace

std::string finding_size(const Finding& f) {
  std::string s;
  for (std::size_t i = 0; i < f.params.size(); ++i) {
    const double err = i < f.stderrs.size() ? f.stderrs[i].value : std::nan("");
    s += fmt::format("{}{} = {}{}", i == 0 ? "" : ", ", f.params[i].name, plus_minus(f.params[i].value, err),
                     unit_of(f.name(), f.params[i].name));
  }
  return s;
}

namespace {

// The summary's first line: what the nominal model leaves out and its
// held-out proof, else the unexplained disagreement, else why nothing.
std::string headline(const Diagnosis& d) {
  std::vector<const Finding*> effects;
  const Finding* unexplained = nullptr;
  for (const Finding& f : d.findings) {
    if (f.is_unexplained()) {
      unexplained = &f;
    } else {
      effects.push_back(&f);
    }
  }

  if (!effects.empty()) {
    std::string what;
    for (std::size_t i = 0; i < effects.size(); ++i) {
      const char* sep = i == 0 ? "" : (i + 1 == effects.size() ? " and " : ", ");
      what += fmt::format("{}{} ({})", sep, words(effects[i]->name()), finding_size(*effects[i]));
    }
    // Held-out proof: the chosen wheel model against the nominal one when a
    // wheel effect was found, else the (gyro) finding's own replay.
    bool wheel = false;
    for (const Finding* f : effects) wheel = wheel || f->is_wheel_effect();
    const BeforeAfter& h = wheel ? d.heldout : effects.front()->heldout;
    std::string proof = "no held-out windows to prove it on";
    if (std::isfinite(h.before_pos_rmse_m) && std::isfinite(h.after_pos_rmse_m) && h.before_pos_rmse_m > 0)
      proof = fmt::format("modelling {} changes the held-out position error from {} to {} ({:+.0f} %)",
                          effects.size() == 1 ? "it" : "them", metres(h.before_pos_rmse_m),
                          metres(h.after_pos_rmse_m), pct_change(h));
    return fmt::format("{}: the nominal model leaves out {}; {}.", d.track, what, proof);
  }
  if (unexplained)
    return unexplained->model && unexplained->model->proven
               ? fmt::format("{}: the model and the recording disagree beyond sensor noise, no effect of "
                             "physics-effects.md explains it, and terms outside that list reproduce it: {}.",
                             d.track, unexplained->model->formula)
               : fmt::format(
                     "{}: the model and the recording disagree at {}{} beyond sensor noise, and no effect of "
                     "physics-effects.md explains it{}.",
                     d.track, spans(unexplained->segments),
                     unexplained->conditions.empty() ? "" : " (" + unexplained->conditions + ")",
                     unexplained->model ? "; terms fitted to it are not proven on the held-out recordings"
                                        : "");
  if (!d.not_confirmed.empty())
    return fmt::format("{}: nothing proven — what the fitted recordings show does not predict the "
                       "held-out recordings (below).",
                       d.track);
  return fmt::format("{}: nothing left out — the nominal model explains the recording within sensor noise "
                     "(held-out position error {} over windows of {:g} s).",
                     d.track, metres(d.heldout.before_pos_rmse_m), d.window_s);
}

// A finding's term model (terms outside physics-effects.md, term_search.h):
// its formula, its terms and their held-out errors.
void add_model_lines(const TermModel& m, std::vector<std::string>& lines) {
  lines.push_back("     model: " + m.formula +
                  (m.proven ? "" : " (fits the fitted data, not proven elsewhere)"));
  std::string t;
  for (const FoundTerm& ft : m.terms)
    t += fmt::format("{}{} on {} = {}", t.empty() ? "" : ", ", ft.name, sim::target_name(ft.term.target),
                     plus_minus(ft.term.coef, ft.std_error));
  lines.push_back(fmt::format("     terms: {} (held-out {} → {})", t, metres(m.heldout.before_pos_rmse_m),
                              metres(m.heldout.after_pos_rmse_m)));
  if (m.other_recordings)
    lines.push_back(fmt::format("     on the held-out recordings: {} → {}",
                                metres(m.other_recordings->before_pos_rmse_m),
                                metres(m.other_recordings->after_pos_rmse_m)));
}

// Finding number i (from 0): its size, share and held-out errors, then where,
// when and why.
void add_finding_lines(const Diagnosis& d, std::size_t i, std::vector<std::string>& lines) {
  const Finding& f = d.findings[i];
  std::string line = fmt::format("  {}. {}", i + 1, f.name());
  if (!f.params.empty()) line += " " + finding_size(f);
  line += fmt::format(" — explains {:.{}f} %; held-out {} → {}", 100.0 * f.explains, f.explains < 0.01 ? 2 : 0,
                      metres(f.heldout.before_pos_rmse_m), metres(f.heldout.after_pos_rmse_m));
  lines.push_back(line);
  if (f.heldout_test) lines.push_back("     held-out recordings: " + describe(*f.heldout_test));
  if (!f.segments.empty()) lines.push_back("     where: " + spans(f.segments));
  for (const MapRegion& r : f.regions)
    lines.push_back(fmt::format("     region: x {:.2f}…{:.2f} m, y {:.2f}…{:.2f} m", r.x0_m, r.x1_m, r.y0_m,
                                r.y1_m));
  if (!f.conditions.empty()) lines.push_back("     when: " + f.conditions);
  if (!d.velocity_source.empty()) {
    const std::string v = velocity_terms(f, d.velocity_source);
    if (!v.empty()) lines.push_back("     in the " + d.velocity_source + "'s terms: " + v);
  }
  if (f.model) add_model_lines(*f.model, lines);
  if (!f.rivals.empty()) {
    std::string r;
    for (Effect e : f.rivals) r += (r.empty() ? "" : ", ") + std::string(effect_name(e));
    lines.push_back("     the data cannot rule out: " + r);
  }
  lines.push_back("     evidence: " + f.evidence);
}

// The last line: the replay's windows, reference and errors.
std::string replay_line(const Diagnosis& d) {
  const std::string against = d.ref_gt_samples > 0 && d.ref_fix_samples > 0
                                  ? fmt::format("{} ground-truth positions and {} position fixes",
                                                d.ref_gt_samples, d.ref_fix_samples)
                              : d.reference == ReferenceKind::gt ? "ground truth"
                                                                 : "position fixes";
  return fmt::format("replay: windows of {:g} s against {}; position RMSE nominal {} → chosen model {}{}",
                     d.window_s, against, metres(d.baseline_pos_rmse_m), metres(d.final_pos_rmse_m),
                     d.note.empty() ? "" : "; note: " + d.note);
}

}  // namespace

std::vector<std::string> diagnosis_summary(const Diagnosis& d) {
  std::vector<std::string> lines;
  lines.push_back(headline(d));
  for (std::size_t i = 0; i < d.findings.size(); ++i) add_finding_lines(d, i, lines);
  for (const ImmaterialEffect& s : d.immaterial) lines.push_back("not a finding (immaterial): " + s.line);
  for (const std::string& s : d.not_reproduced) lines.push_back("not a finding (not reproduced): " + s);
  for (const std::string& s : d.not_confirmed) lines.push_back("not a finding (not confirmed): " + s);
  for (const std::string& s : d.sensor_notes) lines.push_back("sensor check: " + s);
  lines.push_back(replay_line(d));
  return lines;
}

namespace {

// A recording's own sensor checks in the odometry's terms: how far and how
// much it turns against what the odometry (or the command) says, and how
// late the motion is; "" when none was measured.
std::string own_terms(const RecordingResult& r, const std::string& src) {
  std::vector<std::string> parts;
  const std::string what = src.empty() ? "odometry" : src;
  if (std::isfinite(r.speed_ratio))
    parts.push_back(fmt::format("covers {:.1f} % of the distance the {} says", 100.0 * r.speed_ratio, what));
  if (std::isfinite(r.yaw_ratio))
    parts.push_back(fmt::format("turns {:.1f} % of its angle", 100.0 * r.yaw_ratio));
  if (std::isfinite(r.motion_late_s))
    parts.push_back(r.motion_late_s >= 0.0 ? fmt::format("moves {:.3f} s after it", r.motion_late_s)
                                           : fmt::format("moves {:.3f} s before it", -r.motion_late_s));
  if (parts.empty()) return "";
  std::string out = "the robot ";
  for (std::size_t i = 0; i < parts.size(); ++i)
    out += (i == 0 ? "" : i + 1 == parts.size() ? " and " : ", ") + parts[i];
  return out + " (its own sensor checks)";
}

}  // namespace

std::vector<std::string> pooled_summary(const PooledDiagnosis& p) {
  std::vector<std::string> lines = diagnosis_summary(p.pooled);
  lines.push_back(fmt::format("recordings ({} fitted{}); held-out proof from {}:",
                              std::count_if(p.recordings.begin(), p.recordings.end(),
                                            [](const RecordingResult& r) { return !r.heldout; }),
                              p.heldout_recordings ? ", the others held out" : "",
                              p.heldout_recordings ? "the held-out recordings" : "the pooled split"));
  const bool wheel = std::any_of(p.pooled.findings.begin(), p.pooled.findings.end(),
                                 [](const Finding& f) { return f.is_wheel_effect(); });
  if (p.heldout_recordings && wheel) {
    const HeldoutTest& t = p.heldout_test;
    lines.push_back(fmt::format("  the model on the held-out recordings: {} → {} (floor {}), {}: {}",
                                metres(t.error.before_pos_rmse_m), metres(t.error.after_pos_rmse_m),
                                metres(t.floor_m), describe(t), t.proven ? "proven" : "not proven"));
  }
  for (const RecordingResult& r : p.recordings)
    lines.push_back(fmt::format("  {} [{}] {:.0f} s, {} reference samples{}: nominal {} → pooled model {}{}",
                                r.track, r.heldout ? "held out" : "fitted", r.duration_s, r.ref_samples,
                                std::isfinite(r.pooled_time_offset_s) && r.pooled_time_offset_s != 0.0
                                    ? fmt::format(" (pooled time = own + {:.1f} s)", r.pooled_time_offset_s)
                                    : "",
                                metres(r.error.before_pos_rmse_m), metres(r.error.after_pos_rmse_m),
                                r.note.empty() ? "" : " (" + r.note + ")"));
  for (const RecordingResult& r : p.recordings) {
    const std::string m = own_terms(r, p.pooled.velocity_source);
    if (!m.empty()) lines.push_back(fmt::format("  {}: {}", r.track, m));
  }
  for (const std::string& c : p.consistency) lines.push_back("  " + c);
  return lines;
}

}  // namespace odotune::diagnose

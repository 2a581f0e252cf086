#include "diagnose/diagnosis_summary.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tracks/effects.h"
#include "tracks/model_terms.h"

namespace odotune {
namespace {

using namespace odotune::diagnose;

// The effect's name in words: "lateral_skid" -> "lateral skid".
std::string words(const std::string& effect) {
  std::string s = effect;
  std::replace(s.begin(), s.end(), '_', ' ');
  return s;
}

std::string unit_of(const std::string& effect, const std::string& param) {
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

}  // namespace

std::string finding_size(const Finding& f) {
  std::string s;
  for (std::size_t i = 0; i < f.params.size(); ++i) {
    const double err = i < f.stderrs.size() ? f.stderrs[i].value : std::nan("");
    s += fmt::format("{}{} = {}{}", i == 0 ? "" : ", ", f.params[i].name, plus_minus(f.params[i].value, err),
                     unit_of(f.effect, f.params[i].name));
  }
  return s;
}

std::vector<std::string> diagnosis_summary(const Diagnosis& d) {
  std::vector<std::string> lines;
  std::vector<const Finding*> effects;
  const Finding* unexplained = nullptr;
  for (const Finding& f : d.findings) {
    if (f.effect == "unexplained") {
      unexplained = &f;
    } else {
      effects.push_back(&f);
    }
  }

  if (!effects.empty()) {
    std::string what;
    for (std::size_t i = 0; i < effects.size(); ++i) {
      const char* sep = i == 0 ? "" : (i + 1 == effects.size() ? " and " : ", ");
      what += fmt::format("{}{} ({})", sep, words(effects[i]->effect), finding_size(*effects[i]));
    }
    // Held-out proof: the chosen wheel model against the nominal one when a
    // wheel effect was found, else the (gyro) finding's own replay.
    bool wheel = false;
    for (const Finding* f : effects) wheel = wheel || (f->effect != "gyro_bias" && f->effect != "gyro_scale");
    const BeforeAfter& h = wheel ? d.heldout : effects.front()->heldout;
    std::string proof = "no held-out windows to prove it on";
    if (std::isfinite(h.before_pos_rmse_m) && std::isfinite(h.after_pos_rmse_m) && h.before_pos_rmse_m > 0)
      proof = fmt::format("modelling {} changes the held-out position error from {} to {} ({:+.0f} %)",
                          effects.size() == 1 ? "it" : "them", metres(h.before_pos_rmse_m),
                          metres(h.after_pos_rmse_m), pct_change(h));
    lines.push_back(fmt::format("{}: the nominal model leaves out {}; {}.", d.track, what, proof));
  } else if (unexplained) {
    lines.push_back(
        unexplained->model
            ? fmt::format("{}: the model and the recording disagree beyond sensor noise, no effect of "
                          "physics-effects.md explains it, and terms outside that list reproduce it: {}.",
                          d.track, unexplained->model->formula)
            : fmt::format(
                  "{}: the model and the recording disagree at {}{} beyond sensor noise, and no effect of "
                  "physics-effects.md explains it.",
                  d.track, spans(unexplained->segments),
                  unexplained->conditions.empty() ? "" : " (" + unexplained->conditions + ")"));
  } else {
    lines.push_back(
        fmt::format("{}: nothing left out — the nominal model explains the recording within sensor noise "
                    "(held-out position error {} over windows of {:g} s).",
                    d.track, metres(d.heldout.before_pos_rmse_m), d.window_s));
  }

  for (std::size_t i = 0; i < d.findings.size(); ++i) {
    const Finding& f = d.findings[i];
    std::string line = fmt::format("  {}. {}", i + 1, f.effect);
    if (!f.params.empty()) line += " " + finding_size(f);
    line += fmt::format(" — explains {:.{}f} %; held-out {} → {}", 100.0 * f.explains,
                        f.explains < 0.01 ? 2 : 0, metres(f.heldout.before_pos_rmse_m),
                        metres(f.heldout.after_pos_rmse_m));
    lines.push_back(line);
    if (!f.segments.empty()) lines.push_back("     where: " + spans(f.segments));
    for (const MapRegion& r : f.regions)
      lines.push_back(fmt::format("     region: x {:.2f}…{:.2f} m, y {:.2f}…{:.2f} m", r.x0_m, r.x1_m, r.y0_m,
                                  r.y1_m));
    if (!f.conditions.empty()) lines.push_back("     when: " + f.conditions);
    if (f.model) {  // terms outside physics-effects.md (term_search.h)
      lines.push_back("     model: " + f.model->formula);
      std::string t;
      for (const FoundTerm& ft : f.model->terms)
        t += fmt::format("{}{} on {} = {}", t.empty() ? "" : ", ", ft.name, sim::target_name(ft.term.target),
                         plus_minus(ft.term.coef, ft.std_error));
      lines.push_back(fmt::format("     terms: {} (held-out {} → {})", t,
                                  metres(f.model->heldout.before_pos_rmse_m),
                                  metres(f.model->heldout.after_pos_rmse_m)));
    }
    if (!f.rivals.empty()) {
      std::string r;
      for (const std::string& name : f.rivals) r += (r.empty() ? "" : ", ") + name;
      lines.push_back("     the data cannot rule out: " + r);
    }
    lines.push_back("     evidence: " + f.evidence);
  }
  lines.push_back(fmt::format(
      "replay: windows of {:g} s against {}; position RMSE nominal {} → chosen model {}{}", d.window_s,
      d.reference == ReferenceKind::gt ? "ground truth" : "position fixes", metres(d.baseline_pos_rmse_m),
      metres(d.final_pos_rmse_m), d.note.empty() ? "" : "; note: " + d.note));
  return lines;
}

}  // namespace odotune

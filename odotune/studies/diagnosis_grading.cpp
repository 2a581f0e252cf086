#include <odotune/studies/diagnosis_grading.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/robust_stats.h>
#include <odotune/sim/effects.h>

namespace odotune::studies {

namespace {

using diagnose::Effect;
using diagnose::FindingKind;

template <class T, class U>
bool contains(const std::vector<T>& v, const U& x) {
  return std::find(v.begin(), v.end(), T{x}) != v.end();
}

bool is_box_edge(Effect effect, std::string_view p) {
  return effect == Effect::slip_zone && (p == "x0" || p == "x1" || p == "y0" || p == "y1");
}

double departure(const TrueEffect& e, std::string_view param) {
  const sim::EffectInfo* info = sim::find_effect(e.name());
  const sim::EffectParamInfo* p = info ? sim::find_param(*info, param) : nullptr;
  if (p == nullptr) throw std::invalid_argument(fmt::format("{} has no parameter {}", e.name(), param));
  return std::abs(e.param(param) - p->default_value);
}

void join(std::string& why, const std::string& part) { why += (why.empty() ? "" : "; ") + part; }

bool inside(double x, double y, double x0, double x1, double y0, double y1) {
  return x >= x0 && x <= x1 && y >= y0 && y <= y1;
}

}  // namespace

std::string_view to_string(CaseCategory c) {
  switch (c) {
    case CaseCategory::null_case: return "null";
    case CaseCategory::undetectable: return "undetectable";
    case CaseCategory::single: return "single";
    case CaseCategory::two: return "two";
  }
  return "";
}

CaseCategory case_category(const std::vector<EffectTruth>& truth) {
  const auto k = std::count_if(truth.begin(), truth.end(), [](const EffectTruth& t) { return t.detectable; });
  if (k >= 2) return CaseCategory::two;
  if (k == 1) return CaseCategory::single;
  return truth.empty() ? CaseCategory::null_case : CaseCategory::undetectable;
}

double param_tolerance(const TrueEffect& e, std::string_view param, double wheel_base_m) {
  if (e.effect == Effect::radius_step && param == "t") return 5.0;
  if (is_box_edge(e.effect, param))
    throw std::invalid_argument("param_tolerance: slip_zone's box is graded by box_coverage");
  if (param == "scale_l" || param == "scale_r")
    return 0.25 * std::max(departure(e, "scale_l"), departure(e, "scale_r"));
  if (e.effect == Effect::slip_zone) return 0.25 * std::max(departure(e, "s_l"), departure(e, "s_r"));
  if (e.effect == Effect::odometry_bias) {
    const double half = 0.5 * wheel_base_m;
    const double rim = std::max(departure(e, "b_v"), departure(e, "b_w") * half);
    return param == "b_w" ? 0.25 * rim / half : 0.25 * rim;
  }
  return 0.25 * departure(e, param);
}

std::vector<std::pair<double, double>> reference_gaps(const std::vector<double>& ref_t_s) {
  std::vector<std::pair<double, double>> gaps;
  if (ref_t_s.size() < 3) return gaps;
  const double limit = 2.0 * core::median_period_s(ref_t_s, core::MedianRule::upper_middle);
  for (std::size_t i = 0; i + 1 < ref_t_s.size(); ++i)
    if (ref_t_s[i + 1] - ref_t_s[i] > limit) gaps.emplace_back(ref_t_s[i], ref_t_s[i + 1]);
  return gaps;
}

std::vector<std::pair<double, double>> odometry_standstills(const diagnose::DiagInput& in) {
  std::vector<std::pair<double, double>> out;
  const bool wheels = in.odometry == diagnose::OdometryKind::wheel_angles;
  const auto& t = in.odo_t_s;
  const auto still = [&](std::size_t i) {  // no motion over [t[i], t[i+1]]
    if (wheels) return in.phi_l_rad[i + 1] == in.phi_l_rad[i] && in.phi_r_rad[i + 1] == in.phi_r_rad[i];
    return in.v_mps[i] == 0.0 && in.v_mps[i + 1] == 0.0 && in.w_radps[i] == 0.0 && in.w_radps[i + 1] == 0.0;
  };
  const std::size_t n = wheels ? in.phi_l_rad.size() : in.v_mps.size();
  if (n != t.size() || (!wheels && in.w_radps.size() != n)) return out;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (!still(i)) continue;
    std::size_t j = i;
    while (j + 1 < n && still(j)) ++j;
    out.emplace_back(t[i], t[j]);
    i = j;
  }
  return out;
}

double driving_time_between(double a, double b, const std::vector<std::pair<double, double>>& standstills_s) {
  const double lo = std::min(a, b), hi = std::max(a, b);
  double d = hi - lo;
  for (const auto& [s0, s1] : standstills_s) d -= std::max(0.0, std::min(hi, s1) - std::max(lo, s0));
  return std::max(d, 0.0);
}

BoxCoverage box_coverage(const TrueEffect& t, double x0, double x1, double y0, double y1,
                         const TruePath& path) {
  BoxCoverage c;
  int both = 0, only_found = 0;
  for (std::size_t i = 0; i < path.x_m.size(); ++i) {
    const double x = path.x_m[i], y = path.y_m[i];
    const bool in_true = inside(x, y, t.param("x0"), t.param("x1"), t.param("y0"), t.param("y1"));
    const bool in_found = inside(x, y, x0, x1, y0, y1);
    c.samples += in_true ? 1 : 0;
    both += in_true && in_found ? 1 : 0;
    only_found += !in_true && in_found ? 1 : 0;
  }
  if (c.samples > 0) {
    c.covered = static_cast<double>(both) / c.samples;
    c.extra = static_cast<double>(only_found) / c.samples;
  } else {
    c.extra = only_found > 0 ? 1.0 : 0.0;
  }
  return c;
}

namespace {

// Which effects were expected (detectable), tolerated (true but not
// detectable), found, missed and named extra; why a naming fails.
void grade_naming(CaseGrade& g, const std::vector<EffectTruth>& truth, const diagnose::Diagnosis& d) {
  g.category = case_category(truth);
  for (const EffectTruth& t : truth) (t.detectable ? g.expected : g.tolerated).push_back(t.effect.effect);
  for (const diagnose::Finding& f : d.findings)
    if (!contains(g.found, f.kind)) g.found.push_back(f.kind);
  for (Effect e : g.expected)
    if (!contains(g.found, e)) g.missed.push_back(e);
  for (const FindingKind& f : g.found) {
    const Effect* e = std::get_if<Effect>(&f);
    if (e == nullptr || (!contains(g.expected, *e) && !contains(g.tolerated, *e))) g.extra.push_back(f);
  }
  g.named_ok = g.missed.empty() && g.extra.empty();
  g.heldout_before_m = d.heldout.before_pos_rmse_m;
  g.heldout_after_m = d.heldout.after_pos_rmse_m;
  for (Effect e : g.missed) join(g.why, fmt::format("missed {}", diagnose::effect_name(e)));
  for (const FindingKind& e : g.extra) join(g.why, fmt::format("named {}", diagnose::to_string(e)));
}

// The found slip_zone box against the true one: the larger of the share of
// the true box's path it misses and the share it adds.
ParamCheck box_check(const EffectTruth& t, const diagnose::Finding& f, const TruePath& path, CaseGrade& g) {
  const BoxCoverage c = box_coverage(t.effect, f.param("x0"), f.param("x1"), f.param("y0"), f.param("y1"),
                                     path);
  ParamCheck p;
  p.effect = Effect::slip_zone;
  p.param = "box";
  p.truth = 0.0, p.found = std::max(1.0 - c.covered, c.extra), p.tolerance = 0.25;
  p.normalised = p.found;
  p.ok = c.samples > 0 && p.found <= 0.25;
  if (!p.ok)
    join(g.why, fmt::format("slip_zone box covers {:.0f} % of the true box's path, {:.0f} % extra",
                            100 * c.covered, 100 * c.extra));
  return p;
}

// Each parameter of a named true effect against its finding `f` (box edges
// ungraded: the box is graded whole), into g.params.
void grade_params(CaseGrade& g, const EffectTruth& t, const diagnose::Finding& f, double wheel_base_m,
                  const TruePath& path) {
  for (const auto& [name, value] : t.effect.params) {
    ParamCheck p;
    p.effect = t.effect.effect;
    p.param = name;
    p.truth = value;
    p.found = f.param(name);
    if (is_box_edge(t.effect.effect, name)) {
      p.graded = false;
      p.ok = std::isfinite(p.found);
      p.normalised = (p.found - p.truth) / (t.effect.param(name[0] == 'x' ? "x1" : "y1") -
                                            t.effect.param(name[0] == 'x' ? "x0" : "y0"));
      g.params.push_back(p);
      continue;
    }
    p.tolerance = param_tolerance(t.effect, name, wheel_base_m);
    double miss = p.found - p.truth;
    if (t.effect.effect == Effect::radius_step && name == "t") {
      for (const auto& [a, b] : path.ref_gaps_s)
        if (p.truth > a && p.truth < b) miss = p.found < a ? p.found - a : p.found > b ? p.found - b : 0.0;
      // Counted in driving time: standstills between the two do not count.
      const double target = p.found - miss;
      miss = (miss < 0.0 ? -1.0 : 1.0) * driving_time_between(target, p.found, path.standstills_s);
    }
    p.normalised = p.tolerance > 0.0 ? 0.25 * miss / p.tolerance : std::nan("");
    p.ok = std::isfinite(p.found) && std::abs(miss) <= p.tolerance;
    if (!p.ok)
      join(g.why, fmt::format("{}.{} = {:.6g}, truth {:.6g} ± {:.3g}", diagnose::effect_name(p.effect), p.param,
                              p.found, p.truth, p.tolerance));
    g.params_ok = g.params_ok && p.ok;
    g.params.push_back(p);
  }
  if (t.effect.effect == Effect::slip_zone) {
    const ParamCheck p = box_check(t, f, path, g);
    g.params_ok = g.params_ok && p.ok;
    g.params.push_back(p);
  }
}

}  // namespace

CaseGrade grade_case(const std::vector<EffectTruth>& truth, const diagnose::Diagnosis& d, double wheel_base_m,
                     const TruePath& path) {
  CaseGrade g;
  grade_naming(g, truth, d);
  g.params_ok = true;
  g.heldout_ok = true;
  bool wheel_expected = false;
  for (const EffectTruth& t : truth) {
    if (!t.detectable) continue;
    const auto f = std::find_if(d.findings.begin(), d.findings.end(),
                                [&](const diagnose::Finding& x) { return x.is(t.effect.effect); });
    if (f == d.findings.end()) continue;  // missed: reported above
    const bool gyro = diagnose::is_gyro_effect(t.effect.effect);
    wheel_expected = wheel_expected || !gyro;
    if (gyro && !(f->heldout.after_pos_rmse_m < f->heldout.before_pos_rmse_m)) {
      g.heldout_ok = false;
      join(g.why, fmt::format("{} held-out {:.4g} -> {:.4g} m not improved", t.effect.name(),
                              f->heldout.before_pos_rmse_m, f->heldout.after_pos_rmse_m));
    }
    grade_params(g, t, *f, wheel_base_m, path);
  }
  if (wheel_expected && !(d.heldout.after_pos_rmse_m < d.heldout.before_pos_rmse_m)) {
    g.heldout_ok = false;
    join(g.why, fmt::format("held-out {:.4g} -> {:.4g} m not improved", d.heldout.before_pos_rmse_m,
                            d.heldout.after_pos_rmse_m));
  }
  g.pass = g.named_ok && g.params_ok && g.heldout_ok;
  return g;
}

CaseGrade grade_refusal(const std::vector<EffectTruth>& truth, const std::string& message) {
  CaseGrade g;
  g.category = case_category(truth);
  g.refused = true;
  for (const EffectTruth& t : truth) (t.detectable ? g.expected : g.tolerated).push_back(t.effect.effect);
  g.missed = g.expected;
  g.why = "refused: " + message;
  return g;
}

}  // namespace odotune::studies

// The concealed-effect suite (cases in concealed_cases.h):
// every case is simulated and diagnosed end to end (diagnose(): sensor
// checks, model selection, location). Pass rule of the design note: exactly
// the expected effects named (no other finding, `unexplained` included), each
// parameter within expected_tolerance() of the truth (±25 % of the departure,
// ±5 s for a step time; a slip zone's box by the path as the benchmark grades
// it, odotune/studies/diagnosis_grading.h, not edge by edge, since an edge the robot
// never crosses is not determined by the data), and the held-out error improved: the chosen wheel
// model against the nominal one (Diagnosis::heldout) when a wheel effect is
// expected, and each gyro finding's own held-out replay. (A finding's
// "without it" comparison is printed but not required: with two effects
// seen through 1 Hz fixes, dropping the smaller one changes the held-out
// error by less than the fixes' noise, either way.)
// No-effect cases must give no finding at all.
// Findings that matter: an expected effect whose true model is not
// material (odotune/studies/diagnosis_truth.h assess_detectability: the true model's
// held-out gain against odotune/diagnose/materiality.h's floor, the random
// benchmark's rule) is tolerated, named or not, and so is a borderline one
// (true gain below 1.5 floors: what a fit on noisy data recovers scatters
// around the truth's); the clearly material ones are graded as above. The suite's deliberately small effects (2-10 sigma of
// drift over a window) include some below that floor.
//
// kKnownMisses lists the cases the diagnosis does not pass yet, each with why;
// for those the test asserts what does hold (no wrong effect named) and
// prints what was found, so the list stays honest: a case that starts to
// pass fails the test until it is taken off the list.
#include <chrono>
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/diagnosis.h>
#include <odotune/sim/simulator.h>
#include <odotune/studies/diagnosis_grading.h>
#include <odotune/studies/diagnosis_truth.h>

#include "concealed_cases.h"

namespace odotune::diagnose {
namespace {

using concealed::ConcealedCase;
using odotune::studies::assess_detectability;
using odotune::studies::Detectability;
using odotune::studies::EffectTruth;
using odotune::studies::TrueEffect;

// Case name -> why the diagnosis misses it today.
const std::map<std::string, std::string>& known_misses() {
  // Empty since the selection's materiality rule measures the held-out gain as dead
  // reckoning from the window's start (select.h), as the truth does: both
  // former misses (radius_error_unequal_small, radius_step_late: the gain of
  // the last windows passed the floor, the free-anchored gain over every fold
  // did not) now pass.
  static const std::map<std::string, std::string> m;
  return m;
}

struct Verdict {
  bool named_right = true, params_right = true, heldout_improved = true;
  std::set<std::string> found, expected;
  std::string detail;
  bool pass() const { return named_right && params_right && heldout_improved; }
};

// The case's expected findings as the benchmark's truth (odotune/studies/diagnosis_truth.h).
std::vector<TrueEffect> truth_of(const ConcealedCase& c) {
  std::vector<TrueEffect> out;
  for (const concealed::ExpectedFinding& e : c.expected) {
    TrueEffect t;
    t.effect = effect_from_name(e.effect);
    for (const concealed::ExpectedParam& p : e.params) t.params.emplace_back(std::string(p.name), p.value);
    out.push_back(std::move(t));
  }
  return out;
}

// Only material effects are findings. An expected effect whose
// true model is not material (assess_detectability, the benchmark's rule)
// may be named or not; every material one must be named, nothing else.
Verdict judge(const ConcealedCase& c, const Diagnosis& d, const Detectability& truth, const DiagInput& in) {
  Verdict v;
  for (const Finding& f : d.findings) v.found.insert(std::string(f.name()));
  std::set<std::string> tolerated;
  // Borderline: a true gain within kBorderline floors is near what noise lets
  // a fit recover; either verdict is accepted there.
  constexpr double kBorderline = 1.5;
  for (const EffectTruth& t : truth.effects)
    (t.detectable && t.gain_m >= kBorderline * t.floor_m ? v.expected : tolerated)
        .insert(std::string(t.effect.name()));
  v.named_right = true;
  for (const std::string& e : v.expected) v.named_right = v.named_right && v.found.count(e) > 0;
  for (const std::string& e : v.found)
    v.named_right = v.named_right && (v.expected.count(e) || tolerated.count(e));
  for (const EffectTruth& t : truth.effects)
    if (tolerated.count(std::string(t.effect.name())))
      v.detail += std::string(t.effect.name()) + " true gain " + std::to_string(1e3 * t.gain_m) +
                  " mm vs floor " + std::to_string(1e3 * t.floor_m) +
                  " mm: not or barely material (tolerated); ";
  for (const concealed::ExpectedFinding& e : c.expected) {
    if (!v.expected.count(std::string(e.effect))) continue;
    const Finding* f = nullptr;
    for (const Finding& g : d.findings)
      if (g.name() == e.effect) f = &g;
    if (!f) continue;
    for (const concealed::ExpectedParam& p : e.params) {
      if (e.effect == "slip_zone" && p.name.size() == 2 && (p.name[0] == 'x' || p.name[0] == 'y')) continue;
      const double got = f->param(p.name), tol = concealed::expected_tolerance(e, p);
      const bool ok = std::isfinite(got) && std::abs(got - p.value) <= tol;
      v.params_right = v.params_right && ok;
      v.detail += std::string(e.effect) + "." + std::string(p.name) + " = " + std::to_string(got) + " (truth " +
                  std::to_string(p.value) + " ± " + std::to_string(tol) + ")" + (ok ? "" : " OUT") + "; ";
    }
    if (e.effect == "slip_zone") {
      // The box by the path, as the benchmark grades it (diagnosis_grading.h):
      // an edge the robot never crosses is not determined by the data. The
      // path: the reference positions (ground truth with its noise).
      TrueEffect t;
      t.effect = Effect::slip_zone;
      for (const concealed::ExpectedParam& p : e.params) t.params.emplace_back(std::string(p.name), p.value);
      const studies::BoxCoverage b = studies::box_coverage(t, f->param("x0"), f->param("x1"), f->param("y0"),
                                                           f->param("y1"),
                                                           studies::TruePath{in.ref_x_m, in.ref_y_m, {}, {}});
      const bool ok = b.samples > 0 && b.covered >= 0.75 && b.extra <= 0.25;
      v.params_right = v.params_right && ok;
      v.detail += "slip_zone box [" + std::to_string(f->param("x0")) + ", " + std::to_string(f->param("x1")) +
                  "] x [" + std::to_string(f->param("y0")) + ", " + std::to_string(f->param("y1")) +
                  "] covers " + std::to_string(100 * b.covered) + " % of the true box's path, " +
                  std::to_string(100 * b.extra) + " % extra" + (ok ? "" : " OUT") + "; ";
    }
    const bool gyro = e.effect == "gyro_bias" || e.effect == "gyro_scale";
    const BeforeAfter& h = gyro ? f->heldout : d.heldout;
    v.heldout_improved = v.heldout_improved && h.after_pos_rmse_m < h.before_pos_rmse_m;
    v.detail += "held-out " + std::to_string(f->heldout.before_pos_rmse_m) + " -> " +
                std::to_string(f->heldout.after_pos_rmse_m) + " m (without it -> all)" +
                (gyro ? ""
                      : ", nominal -> chosen " + std::to_string(d.heldout.before_pos_rmse_m) + " -> " +
                            std::to_string(d.heldout.after_pos_rmse_m) + " m") +
                "; ";
  }
  return v;
}

std::string set_text(const std::set<std::string>& s) {
  std::string out;
  for (const std::string& e : s) out += (out.empty() ? "" : ", ") + e;
  return out.empty() ? "none" : out;
}

class ConcealedDiagnosis : public ::testing::TestWithParam<std::size_t> {};

TEST_P(ConcealedDiagnosis, NamesTheEffectsWithinToleranceAndProvesThemHeldOut) {
  const ConcealedCase& c = concealed::concealed_cases().at(GetParam());
  const auto t0 = std::chrono::steady_clock::now();
  const DiagInput in = build_diag_input(sim::simulate(concealed::base_scenario(c)));
  const Diagnosis d = diagnose(in);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Verdict v = judge(c, d, studies::assess_detectability(in, truth_of(c)), in);
  std::cout << "[ concealed ] " << c.name << ": found {" << set_text(v.found) << "} expected {"
            << set_text(v.expected) << "} " << v.detail << secs << " s\n";
  SCOPED_TRACE(std::string(c.name) + ": " + std::string(c.why_hard));
  const auto miss = known_misses().find(std::string(c.name));
  if (miss == known_misses().end()) {
    EXPECT_TRUE(v.named_right) << "found {" << set_text(v.found) << "}, expected {" << set_text(v.expected)
                               << "}";
    EXPECT_TRUE(v.params_right) << v.detail;
    EXPECT_TRUE(v.heldout_improved) << v.detail;
    return;
  }
  // A known miss: nothing wrong is named, and it still misses (else take it off the list).
  for (const std::string& e : v.found)
    EXPECT_TRUE(v.expected.count(e)) << "named " << e << ", which the case does not have";
  EXPECT_FALSE(v.pass()) << c.name << " passes now: remove it from known_misses()";
}

INSTANTIATE_TEST_SUITE_P(Suite, ConcealedDiagnosis,
                         ::testing::Range<std::size_t>(0, concealed::concealed_cases().size()),
                         [](const ::testing::TestParamInfo<std::size_t>& p) {
                           return std::string(concealed::concealed_cases().at(p.param).name);
                         });

TEST(ConcealedDiagnosis, KnownMissesNameRealCasesAndLeaveMostPassing) {
  std::set<std::string> names;
  for (const ConcealedCase& c : concealed::concealed_cases()) names.insert(std::string(c.name));
  for (const auto& [name, why] : known_misses()) {
    EXPECT_TRUE(names.count(name)) << name;
    EXPECT_FALSE(why.empty()) << name;
  }
  EXPECT_LE(known_misses().size() * 4, names.size()) << "more than a quarter of the suite missed";
}

}  // namespace
}  // namespace odotune::diagnose

// The random diagnosis benchmark (studies/diagnosis_*.h): the case generator
// is deterministic per case seed and for any thread count, respects what each
// effect needs and shapes every reference as asked; the grading rules on
// hand-made diagnoses; the summary's counts; and one tiny end-to-end run
// that writes consistent files.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <odotune/core/failure.h>
#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/recordings.h>
#include <odotune/sim/effects.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/simulator.h>
#include <odotune/studies/diagnosis_benchmark.h>
#include <odotune/studies/diagnosis_benchmark_outputs.h>
#include <odotune/studies/diagnosis_drives.h>

#include "support/temp_dir.h"

namespace odotune::studies {
namespace {

// Short single-recording cases (the multi-recording tests ask for theirs).
CaseDrawOptions short_draws() {
  CaseDrawOptions o;
  o.min_minutes = 0.5, o.max_minutes = 1.0, o.max_rate_hz = 20.0;
  o.multi_share = 0.0;
  return o;
}

bool same_track(const tracks::Track& a, const tracks::Track& b) {
  const tracks::TrackData &x = a.data(), &y = b.data();
  if (x.t != y.t || x.ticks_l != y.ticks_l || x.ticks_r != y.ticks_r) return false;
  for (int k = 0; k < tracks::kNumCols; ++k) {
    if (x.cols[k].size() != y.cols[k].size()) return false;
    for (std::size_t i = 0; i < x.cols[k].size(); ++i) {
      const double u = x.cols[k][i], v = y.cols[k][i];
      if (!(u == v || (std::isnan(u) && std::isnan(v)))) return false;
    }
  }
  return true;
}

// ---------------------------------------------------------------- generator

TEST(DiagnosisCases, SameSeedSameCaseAndTrackForAnyThreadCount) {
  const CaseDrawOptions o = short_draws();
  constexpr int kCases = 4;
  std::vector<std::string> text[2];
  std::vector<tracks::Track> tracks[2];
  for (int run = 0; run < 2; ++run) {
    text[run].resize(kCases);
    std::vector<std::optional<tracks::Track>> t(kCases);
#pragma omp parallel for schedule(dynamic, 1) num_threads(run == 0 ? 1 : 2)
    for (int i = 0; i < kCases; ++i) {
      const DiagnosisCase c = draw_case(case_seed(77, i), i, o);
      text[run][static_cast<std::size_t>(i)] = c.robot + "|" + c.drive + "|" + c.effects_text() + "|" +
                                               std::string(to_string(c.reference)) + "|" +
                                               std::string(to_string(c.odometry));
      t[static_cast<std::size_t>(i)] = make_case_track(c).track;
    }
    for (auto& x : t) tracks[run].push_back(*x);
  }
  EXPECT_EQ(text[0], text[1]);
  for (int i = 0; i < kCases; ++i) EXPECT_TRUE(same_track(tracks[0][i], tracks[1][i])) << "case " << i;
  // A different seed gives different cases; case seeds differ per index.
  EXPECT_NE(case_seed(77, 0), case_seed(77, 1));
  EXPECT_NE(case_seed(77, 0), case_seed(78, 0));
  const DiagnosisCase other = draw_case(case_seed(78, 0), 0, o);
  EXPECT_NE(other.robot + other.drive, text[0][0].substr(0, other.robot.size() + other.drive.size() + 1));
}

TEST(DiagnosisCases, DrawsRespectWhatEachEffectNeeds) {
  CaseDrawOptions o = short_draws();
  o.min_minutes = 2.0, o.max_minutes = 4.0;
  std::set<std::string> effects, references, odometries;
  int counts[3] = {0, 0, 0};
  constexpr int kDraws = 300;
  for (int i = 0; i < kDraws; ++i) {
    const DiagnosisCase c = draw_case(case_seed(5, i), i, o);
    SCOPED_TRACE("case " + std::to_string(i) + ": " + c.effects_text());
    ASSERT_LE(c.effects.size(), 2u);
    ++counts[c.effects.size()];
    references.insert(std::string(to_string(c.reference)));
    odometries.insert(std::string(to_string(c.odometry)));
    const double dur = sim::MotionProfile(c.scenario.motion).duration_s();
    EXPECT_GE(dur, c.duration_s);
    EXPECT_GE(c.duration_s, 120.0);
    EXPECT_LE(c.duration_s, 240.0);
    EXPECT_LE(c.odo_rate_hz, 20.0);
    std::string why;
    EXPECT_TRUE(sim::validate_scenario(c.scenario, &why)) << why;
    EXPECT_EQ(sim::active_effects(c.scenario.effects).size(), c.effects.size());
    for (const TrueEffect& e : c.effects) {
      effects.insert(std::string(e.name()));
      if (e.effect == diagnose::Effect::gyro_bias || e.effect == diagnose::Effect::gyro_scale) {
        EXPECT_GT(c.gyro_rate_hz, 0.0);
      }
      if (e.effect == diagnose::Effect::actuator_lag) {
        EXPECT_EQ(c.odometry, BenchOdometry::commands);
      }
      if (e.effect == diagnose::Effect::radius_step) {
        EXPECT_GE(e.param("t"), 0.29 * c.duration_s);
        EXPECT_LE(e.param("t"), 0.81 * c.duration_s);
      }
      if (e.effect == diagnose::Effect::slip_zone) {
        // The commanded path crosses the box on its first lap at least.
        const PathSamples p = commanded_path(c.scenario.motion, 0.1);
        int inside = 0;
        for (std::size_t k = 0; k < p.t_s.size(); ++k)
          inside += p.x_m[k] >= e.param("x0") && p.x_m[k] <= e.param("x1") && p.y_m[k] >= e.param("y0") &&
                    p.y_m[k] <= e.param("y1");
        EXPECT_GT(inside, 0);
      }
    }
  }
  // Every effect, every reference shape and odometry source occurs, in roughly
  // the asked shares (1/3 each, +-0.1).
  EXPECT_EQ(effects.size(), sim::effect_table().size());
  EXPECT_EQ(references.size(), 5u);
  EXPECT_EQ(odometries.size(), 3u);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(counts[k] / double(kDraws), 1.0 / 3.0, 0.1) << k << " effects";
}

TEST(DiagnosisCases, TracksHaveTheirReferenceShape) {
  const CaseDrawOptions o = short_draws();
  std::set<BenchReference> seen;
  bool wheel_rates = false;
  for (int i = 0; i < 200 && (seen.size() < 5 || !wheel_rates); ++i) {
    const DiagnosisCase c = draw_case(case_seed(9, i), i, o);
    if (seen.count(c.reference) && (wheel_rates || c.odometry != BenchOdometry::wheel_rates)) continue;
    seen.insert(c.reference);
    const CaseTrack ct = make_case_track(c);
    const tracks::Track& t = ct.track;
    SCOPED_TRACE(std::string(to_string(c.reference)));
    EXPECT_FALSE(ct.path_x_m.empty());
    std::vector<double> gt_t, fix_t;
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (t.at(tracks::Col::gt_x, k)) gt_t.push_back(t.t()[k]);
      if (t.at(tracks::Col::aps_x, k)) fix_t.push_back(t.t()[k]);
    }
    if (c.odometry == BenchOdometry::wheel_rates) {
      wheel_rates = true;
      EXPECT_FALSE(t.has_ticks());
      EXPECT_TRUE(t.has_wheel_rates());
    }
    switch (c.reference) {
      case BenchReference::gt_full:
        EXPECT_GT(gt_t.size(), 100u);
        EXPECT_TRUE(fix_t.empty());
        break;
      case BenchReference::gt_gaps:
        ASSERT_FALSE(c.gt_gaps_s.empty());
        for (double x : gt_t)
          for (const auto& [a, b] : c.gt_gaps_s) EXPECT_FALSE(x >= a && x < b) << x;
        EXPECT_GT(gt_t.size(), 50u);
        break;
      case BenchReference::start_fixes:
        ASSERT_EQ(gt_t.size(), 1u);
        EXPECT_EQ(gt_t[0], t.t().front());
        EXPECT_GT(fix_t.size(), 10u);
        break;
      case BenchReference::fixes:
        EXPECT_FALSE(t.has_gt());
        EXPECT_FALSE(t.meta().get("sim.gt_sigma_m").has_value());
        EXPECT_GT(fix_t.size(), 10u);
        break;
      case BenchReference::fixes_irregular: {
        EXPECT_FALSE(t.has_gt());
        ASSERT_GT(fix_t.size(), 10u);
        double lo = 1e9, hi = 0.0;
        for (std::size_t k = 1; k < fix_t.size(); ++k)
          lo = std::min(lo, fix_t[k] - fix_t[k - 1]), hi = std::max(hi, fix_t[k] - fix_t[k - 1]);
        EXPECT_GT(hi, 2.0 * lo);  // irregular
        const double mean = (fix_t.back() - fix_t.front()) / static_cast<double>(fix_t.size() - 1);
        EXPECT_NEAR(mean * c.fix_rate_hz, 1.0, 0.35);
        break;
      }
    }
  }
  EXPECT_EQ(seen.size(), 5u);
  EXPECT_TRUE(wheel_rates);
}

// ---------------------------------------------------------------- grading

TrueEffect effect(const std::string& name, std::vector<std::pair<std::string, double>> params) {
  TrueEffect e;
  e.effect = diagnose::effect_from_name(name);
  e.params = std::move(params);
  return e;
}

// The names of graded effects or findings, to compare with a list of names.
template <class T>
std::vector<std::string> names(const std::vector<T>& v) {
  std::vector<std::string> out;
  for (const T& x : v) out.emplace_back(diagnose::to_string(diagnose::FindingKind{x}));
  return out;
}

EffectTruth truth_of(TrueEffect e, bool detectable) {
  EffectTruth t;
  t.effect = std::move(e);
  t.detectable = detectable;
  t.gyro = diagnose::is_gyro_effect(t.effect.effect);
  return t;
}

diagnose::Finding finding(const std::string& name, std::vector<diagnose::NamedValue> params,
                          double before = 0.2, double after = 0.1) {
  diagnose::Finding f;
  f.kind = diagnose::finding_kind_from_name(name);
  f.params = std::move(params);
  f.heldout = {before, after};
  return f;
}

diagnose::Diagnosis diagnosis(std::vector<diagnose::Finding> findings, double before = 0.2,
                              double after = 0.05) {
  diagnose::Diagnosis d;
  d.findings = std::move(findings);
  d.heldout = {before, after};
  return d;
}

const TruePath kNoPath;

TEST(DiagnosisGrading, RightEffectWithinToleranceAndImprovedPasses) {
  const std::vector<EffectTruth> truth = {truth_of(effect("lateral_skid", {{"k", 0.04}}), true)};
  const CaseGrade g = grade_case(truth, diagnosis({finding("lateral_skid", {{"k", 0.045}})}), 0.4, kNoPath);
  EXPECT_EQ(g.category, CaseCategory::single);
  EXPECT_TRUE(g.pass) << g.why;
  ASSERT_EQ(g.params.size(), 1u);
  EXPECT_NEAR(g.params[0].tolerance, 0.01, 1e-12);
  EXPECT_NEAR(g.params[0].normalised, 0.125, 1e-12);
}

TEST(DiagnosisGrading, ParameterOutOfToleranceFails) {
  const std::vector<EffectTruth> truth = {truth_of(effect("lateral_skid", {{"k", 0.04}}), true)};
  const CaseGrade g = grade_case(truth, diagnosis({finding("lateral_skid", {{"k", 0.0511}})}), 0.4, kNoPath);
  EXPECT_FALSE(g.pass);
  EXPECT_TRUE(g.named_ok);
  EXPECT_FALSE(g.params_ok);
  EXPECT_NE(g.why.find("lateral_skid.k"), std::string::npos) << g.why;
}

TEST(DiagnosisGrading, ExtraFindingFailsUnexplainedIncluded) {
  const std::vector<EffectTruth> truth = {truth_of(effect("wheel_base_error", {{"scale", 1.02}}), true)};
  for (const char* extra : {"unexplained", "time_offset"}) {
    const CaseGrade g = grade_case(
        truth, diagnosis({finding("wheel_base_error", {{"scale", 1.021}}), finding(extra, {})}), 0.4, kNoPath);
    EXPECT_FALSE(g.pass) << extra;
    EXPECT_EQ(names(g.extra), std::vector<std::string>{extra});
    EXPECT_TRUE(g.params_ok);
  }
}

TEST(DiagnosisGrading, NullCaseWithAnyFindingFailsAndWithoutPasses) {
  const CaseGrade clean = grade_case({}, diagnosis({}), 0.4, kNoPath);
  EXPECT_EQ(clean.category, CaseCategory::null_case);
  EXPECT_TRUE(clean.pass);
  const CaseGrade noisy = grade_case({}, diagnosis({finding("unexplained", {})}), 0.4, kNoPath);
  EXPECT_FALSE(noisy.pass);
  EXPECT_EQ(names(noisy.extra), std::vector<std::string>{"unexplained"});
}

TEST(DiagnosisGrading, UndetectableEffectsAreTolerated) {
  // Two effects, one detectable: graded on it; naming the other is no error,
  // missing it neither.
  const std::vector<EffectTruth> truth = {truth_of(effect("gyro_bias", {{"b", 1e-4}}), false),
                                          truth_of(effect("time_offset", {{"dt", 0.05}}), true)};
  EXPECT_EQ(case_category(truth), CaseCategory::single);
  EXPECT_TRUE(grade_case(truth, diagnosis({finding("time_offset", {{"dt", 0.052}})}), 0.4, kNoPath).pass);
  EXPECT_TRUE(
      grade_case(truth,
                 diagnosis({finding("time_offset", {{"dt", 0.052}}), finding("gyro_bias", {{"b", 9e-3}})}), 0.4,
                 kNoPath)
          .pass);
  const CaseGrade missed = grade_case(truth, diagnosis({finding("gyro_bias", {{"b", 1e-4}})}), 0.4, kNoPath);
  EXPECT_FALSE(missed.pass);
  EXPECT_EQ(names(missed.missed), std::vector<std::string>{"time_offset"});
  const std::vector<EffectTruth> none_detectable = {truth_of(effect("gyro_bias", {{"b", 1e-4}}), false)};
  EXPECT_EQ(case_category(none_detectable), CaseCategory::undetectable);
}

TEST(DiagnosisGrading, HeldOutMustImprove) {
  const std::vector<EffectTruth> wheel = {
      truth_of(effect("radius_error", {{"scale_l", 1.01}, {"scale_r", 1.0}}), true)};
  const CaseGrade flat = grade_case(
      wheel, diagnosis({finding("radius_error", {{"scale_l", 1.01}, {"scale_r", 1.0}})}, 0.1, 0.1), 0.4,
      kNoPath);
  EXPECT_FALSE(flat.pass);
  EXPECT_FALSE(flat.heldout_ok);
  // A gyro finding is proven by its own held-out numbers.
  const std::vector<EffectTruth> gyro = {truth_of(effect("gyro_scale", {{"s", 1.01}}), true)};
  EXPECT_FALSE(
      grade_case(gyro, diagnosis({finding("gyro_scale", {{"s", 1.01}}, 0.3, 0.31)}), 0.4, kNoPath).pass);
  EXPECT_TRUE(grade_case(gyro, diagnosis({finding("gyro_scale", {{"s", 1.01}}, 0.3, 0.2)}, 0.1, 0.1), 0.4,
                         kNoPath)
                  .pass);
}

TEST(DiagnosisGrading, ToleranceRulesForNoOpLikeParameters) {
  // Scale pairs: 25 % of the larger departure, for the wheel that is not off too.
  const TrueEffect re = effect("radius_error", {{"scale_l", 1.008}, {"scale_r", 1.0}});
  EXPECT_NEAR(param_tolerance(re, "scale_l", 0.4), 0.002, 1e-12);
  EXPECT_NEAR(param_tolerance(re, "scale_r", 0.4), 0.002, 1e-12);
  // radius_step.t: 5 s.
  const TrueEffect step = effect("radius_step", {{"t", 100}, {"scale_l", 0.99}, {"scale_r", 0.99}});
  EXPECT_EQ(param_tolerance(step, "t", 0.4), 5.0);
  const std::vector<EffectTruth> truth = {truth_of(step, true)};
  // The step found at t_s (scales within tolerance), graded against `path`.
  const auto step_at_passes = [&](double t_s, const TruePath& path) {
    return grade_case(
               truth,
               diagnosis({finding("radius_step", {{"t", t_s}, {"scale_l", 0.991}, {"scale_r", 0.9905}})}), 0.4,
               path)
        .pass;
  };
  EXPECT_TRUE(step_at_passes(104.5, kNoPath));
  EXPECT_FALSE(step_at_passes(105.5, kNoPath));
  // A step inside a reference gap: anywhere in the gap +-5 s (no sample tells where).
  TruePath gapped = kNoPath;
  gapped.ref_gaps_s = {{95.0, 115.0}};
  EXPECT_TRUE(step_at_passes(114.0, gapped));
  EXPECT_FALSE(step_at_passes(120.5, gapped));
  EXPECT_EQ(reference_gaps({0.0, 1.0, 2.0, 3.0, 9.0, 10.0, 11.0}),
            (std::vector<std::pair<double, double>>{{3.0, 9.0}}));
  // Standstills between the found and the true step time do not count: 8 s
  // apart with 4 s standing still is 4 s of driving (the wheels did not turn).
  TruePath still = kNoPath;
  still.standstills_s = {{101.0, 105.0}};
  EXPECT_TRUE(step_at_passes(108.0, still));
  EXPECT_FALSE(step_at_passes(110.5, still));
  EXPECT_DOUBLE_EQ(driving_time_between(108.0, 100.0, still.standstills_s), 4.0);
  EXPECT_DOUBLE_EQ(driving_time_between(102.0, 104.0, still.standstills_s), 0.0);
  diagnose::DiagInput odo;
  odo.odometry = diagnose::OdometryKind::wheel_angles;
  odo.odo_t_s = {0.0, 1.0, 2.0, 3.0, 4.0, 5.0};
  odo.phi_l_rad = {0.0, 1.0, 1.0, 1.0, 2.0, 3.0};
  odo.phi_r_rad = {0.0, 1.0, 1.0, 1.0, 1.0, 2.0};
  EXPECT_EQ(odometry_standstills(odo), (std::vector<std::pair<double, double>>{{1.0, 3.0}}));
  odo.odometry = diagnose::OdometryKind::body_velocity;
  odo.v_mps = {0.0, 0.0, 0.0, 0.5, 0.0, 0.0};
  odo.w_radps = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(odometry_standstills(odo), (std::vector<std::pair<double, double>>{{0.0, 2.0}, {4.0, 5.0}}));
  // odometry_bias: the larger departure as a rim speed, max(|b_v|, |b_w| D/2).
  const TrueEffect ob = effect("odometry_bias", {{"b_v", 0.0}, {"b_w", 0.01}});
  EXPECT_NEAR(param_tolerance(ob, "b_v", 0.4), 0.25 * 0.002, 1e-12);
  EXPECT_NEAR(param_tolerance(ob, "b_w", 0.4), 0.25 * 0.01, 1e-12);
}

TEST(DiagnosisGrading, SlipZoneBoxIsGradedByThePath) {
  // A path along y = 0 from x = 0 to 10; the true box covers x in [4, 6].
  TruePath path;
  for (int i = 0; i <= 100; ++i) path.x_m.push_back(0.1 * i), path.y_m.push_back(0.0);
  const TrueEffect zone = effect("slip_zone",
                                 {{"x0", 4}, {"x1", 6}, {"y0", -0.5}, {"y1", 0.5}, {"s_l", 0.1}, {"s_r", 0.1}});
  // Edges across the path are not determined: a much wider box that covers
  // the same stretch of path is right.
  EXPECT_NEAR(box_coverage(zone, 4.1, 6.1, -3, 3, path).covered, 20.0 / 21.0, 1e-9);
  const std::vector<EffectTruth> truth = {truth_of(zone, true)};
  auto found = [](double x0, double x1) {
    return finding("slip_zone",
                   {{"x0", x0}, {"x1", x1}, {"y0", -3}, {"y1", 3}, {"s_l", 0.105}, {"s_r", 0.095}});
  };
  EXPECT_TRUE(grade_case(truth, diagnosis({found(4.1, 6.1)}), 0.4, path).pass);
  // Half the stretch missed, or twice as long: wrong.
  EXPECT_FALSE(grade_case(truth, diagnosis({found(5.0, 6.0)}), 0.4, path).pass);
  EXPECT_FALSE(grade_case(truth, diagnosis({found(3.0, 7.0)}), 0.4, path).pass);
}

TEST(DiagnosisGrading, RefusalFailsWithItsMessage) {
  const std::vector<EffectTruth> truth = {truth_of(effect("lateral_skid", {{"k", 0.04}}), true)};
  const CaseGrade g = grade_refusal(truth, "track 'x': 1 ground-truth sample(s)");
  EXPECT_FALSE(g.pass);
  EXPECT_TRUE(g.refused);
  EXPECT_EQ(names(g.missed), std::vector<std::string>{"lateral_skid"});
  EXPECT_NE(g.why.find("1 ground-truth sample"), std::string::npos);
}

// ---------------------------------------------------------------- summary

CaseResult graded(std::vector<EffectTruth> truth, const diagnose::Diagnosis& d) {
  CaseResult r;
  r.truth.effects = truth;
  r.grade = grade_case(truth, d, 0.4, kNoPath);
  r.diagnose_s = 1.0;
  return r;
}

TEST(DiagnosisBenchmarkSummary, CountsConfusionRecallAndPrecision) {
  const EffectTruth skid = truth_of(effect("lateral_skid", {{"k", 0.04}}), true);
  const EffectTruth lag = truth_of(effect("time_offset", {{"dt", 0.05}}), true);
  std::vector<CaseResult> cases = {
      graded({skid}, diagnosis({finding("lateral_skid", {{"k", 0.04}})})),          // right
      graded({skid}, diagnosis({finding("wheel_base_error", {{"scale", 1.01}})})),  // confused
      graded({skid, lag},
             diagnosis({finding("lateral_skid", {{"k", 0.04}}), finding("time_offset", {{"dt", 0.05}})})),
      graded({}, diagnosis({})),                            // null right
      graded({}, diagnosis({finding("unexplained", {})})),  // null false finding
  };
  const BenchmarkSummary s = summarise(cases);
  const CategoryRates& rates = s.single_recording;
  EXPECT_EQ(rates.single.cases, 2);
  EXPECT_EQ(rates.single.passed, 1);
  EXPECT_EQ(rates.two.cases, 1);
  EXPECT_EQ(rates.two.passed, 1);
  EXPECT_EQ(rates.null_cases.cases, 2);
  EXPECT_EQ(rates.null_with_finding, 1);
  EXPECT_DOUBLE_EQ(rates.null_finding_share(), 0.5);
  EXPECT_EQ(s.all.cases, 5);
  const Confusion& c = s.confusion;
  auto at = [&](const std::string& row, const std::string& col) {
    const auto r = std::find(c.rows.begin(), c.rows.end(), row) - c.rows.begin();
    const auto k = std::find(c.cols.begin(), c.cols.end(), col) - c.cols.begin();
    return c.counts[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)];
  };
  EXPECT_EQ(at("lateral_skid", "lateral_skid"), 2);
  EXPECT_EQ(at("lateral_skid", "wheel_base_error"), 1);
  EXPECT_EQ(at("time_offset", "time_offset"), 1);
  EXPECT_EQ(at("none", "none"), 1);
  EXPECT_EQ(at("none", "unexplained"), 1);
  int total = 0;
  for (const auto& row : c.counts)
    for (int v : row) total += v;
  EXPECT_EQ(total, 6);
  const auto skid_score = std::find_if(s.effects.begin(), s.effects.end(), [](const EffectScore& e) {
    return e.effect == diagnose::FindingKind{diagnose::Effect::lateral_skid};
  });
  ASSERT_NE(skid_score, s.effects.end());
  EXPECT_EQ(skid_score->expected, 3);
  EXPECT_NEAR(skid_score->recall(), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(skid_score->precision(), 1.0, 1e-12);
  EXPECT_EQ(s.failures.at("named a wrong effect"), 2);
  EXPECT_EQ(s.failures.at("missed an effect"), 1);
}

// An effect's truth with its gain and floor (and heading gain and floor when given).
EffectTruth with_margin(EffectTruth t, double gain_m, double floor_m, double heading_gain_rad = std::nan(""),
                        double heading_floor_rad = std::nan("")) {
  t.gain_m = gain_m, t.floor_m = floor_m;
  t.heading_gain_rad = heading_gain_rad, t.heading_floor_rad = heading_floor_rad;
  return t;
}

TEST(DiagnosisBenchmarkSummary, RatesByMarginBucket) {
  const TrueEffect skid = effect("lateral_skid", {{"k", 0.04}});
  const TrueEffect offset = effect("time_offset", {{"dt", 0.05}});
  const diagnose::Diagnosis right = diagnosis({finding("lateral_skid", {{"k", 0.04}})});
  const diagnose::Diagnosis wrong = diagnosis({});
  const diagnose::Diagnosis both = diagnosis({finding("lateral_skid", {{"k", 0.04}}),
                                              finding("time_offset", {{"dt", 0.05}})});
  const EffectTruth hidden = with_margin(truth_of(offset, false), 0.1, 1.0);  // not detectable: no margin
  std::vector<CaseResult> cases = {
      graded({with_margin(truth_of(skid, true), 1.2, 1.0)}, right),              // under 1.5, right
      graded({with_margin(truth_of(skid, true), 1.5, 1.0), hidden}, wrong),      // 1.5-3 (1.5 itself), wrong
      graded({with_margin(truth_of(skid, true), 5.0, 2.0)}, right),              // 1.5-3 (2.5), right
      graded({with_margin(truth_of(skid, true), 3.0, 1.0)}, right),              // 3 or more (3 itself), right
      graded({with_margin(truth_of(skid, true), 0.5, 1.0, 0.04, 0.01)}, wrong),  // heading: 4 floors, wrong
      graded({with_margin(truth_of(skid, true), 9.0, 1.0)}, right),              // 3 or more, right
      graded({with_margin(truth_of(skid, true), 9.0, 1.0), with_margin(truth_of(offset, true), 1.6, 1.0)},
             both),  // two effects: the smaller margin, 1.6
      graded({with_margin(truth_of(skid, true), 4.0, 1.0), with_margin(truth_of(offset, true), 3.5, 1.0)},
             wrong),  // two effects, 3.5
  };
  EXPECT_DOUBLE_EQ(case_margin(cases[1].truth), 1.5);
  EXPECT_DOUBLE_EQ(case_margin(cases[4].truth), 4.0);
  EXPECT_DOUBLE_EQ(case_margin(cases[6].truth), 1.6);
  EXPECT_TRUE(std::isinf(case_margin(Detectability{})));
  EXPECT_EQ(margin_bucket(1.4999), MarginBucket::under_1_5);
  EXPECT_EQ(margin_bucket(1.5), MarginBucket::from_1_5_to_3);
  EXPECT_EQ(margin_bucket(3.0), MarginBucket::from_3);
  const CategoryRates k = summarise(cases).single_recording;
  auto counts = [](const Rate& r) { return std::pair{r.passed, r.cases}; };
  const auto under = static_cast<std::size_t>(MarginBucket::under_1_5);
  const auto mid = static_cast<std::size_t>(MarginBucket::from_1_5_to_3);
  const auto top = static_cast<std::size_t>(MarginBucket::from_3);
  EXPECT_EQ(counts(k.single_by_margin[under]), std::pair(1, 1));
  EXPECT_EQ(counts(k.single_by_margin[mid]), std::pair(1, 2));
  EXPECT_EQ(counts(k.single_by_margin[top]), std::pair(2, 3));
  EXPECT_EQ(counts(k.two_by_margin[under]), std::pair(0, 0));
  EXPECT_EQ(counts(k.two_by_margin[mid]), std::pair(1, 1));
  EXPECT_EQ(counts(k.two_by_margin[top]), std::pair(0, 1));
  EXPECT_EQ(counts(k.single), std::pair(4, 6));
  EXPECT_EQ(counts(k.two), std::pair(1, 2));
  // A multi-recording case counts in its own rates only.
  cases[0].c.recordings.resize(2);
  const BenchmarkSummary with_multi = summarise(cases);
  EXPECT_EQ(counts(with_multi.single_recording.single_by_margin[under]), std::pair(0, 0));
  EXPECT_EQ(counts(with_multi.multi_recording.single_by_margin[under]), std::pair(1, 1));
  EXPECT_EQ(counts(with_multi.multi_recording.single), std::pair(1, 1));
  EXPECT_EQ(counts(with_multi.all), std::pair(5, 8));
}

// ---------------------------------------------------------------- end to end

std::string read_file(const std::filesystem::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// A development case the diagnosis once got wrong, run alone and graded:
// `expected` are its detectable effects (empty: a null case, which must give
// no finding at all).
void expect_right(std::uint64_t seed, int index, const std::vector<std::string>& expected) {
  DiagnosisBenchmarkOptions o;
  o.seed = seed;
  o.draw.multi_share = 0.0;  // the single-recording case it was (the draws do not depend on the share)
  const CaseResult c = run_benchmark_case(o, index);
  SCOPED_TRACE("seed " + std::to_string(seed) + " case " + std::to_string(index));
  EXPECT_EQ(names(c.grade.expected), expected);
  if (expected.empty()) {
    EXPECT_EQ(c.grade.category, CaseCategory::null_case);
    EXPECT_TRUE(c.findings.empty());
  }
  EXPECT_TRUE(c.grade.pass) << c.grade.why;
}

// Cases of development seed 1001 that the diagnosis once got wrong:
// 50, a null track on ground truth with gaps whose random wheel slip made
// residuals grow (named `unexplained` until an unexplained finding had to be
// reproduced by the term search on held-out windows); 98, a lateral skid on
// ground truth with a 15 s gap inside one 20 s window (missed until windows
// stopped dead-reckoning across gaps).
TEST(DiagnosisBenchmarkRun, DevelopmentCasesOnceWrongAreRight) {
  expect_right(1001, 50, {});
  expect_right(1001, 98, {"lateral_skid"});
}

// Case 40 of development seed 1004: a null track whose 360-cpr encoders
// lost to the commands beside them; actuator_lag + time_offset passed as a
// pair, the backward pass dropped time_offset and kept actuator_lag at
// tau = 0.14 ms, whose no-op (the commands) did as well (diagnosis-design.md "Model selection", "Swaps":
// the own-parameters rule again in the backward pass).
TEST(DiagnosisBenchmarkRun, PairSurvivorMustStillMatterAlone) { expect_right(1004, 40, {}); }

// Case 119 of development seed 1004: slips of 0.013/0.014 in a 2.7 m patch,
// 1 Hz fixes. The coarse grid's 4 m box diluted them to 0.004/0.008, under the
// 0.01 below which a box was never refined, and a radius step + lateral skid
// was named instead (zone_boxes.h: a box whose fit cost falls by 11.23 or
// more is refined whatever its slips).
TEST(DiagnosisBenchmarkRun, DilutedSlipZoneIsRefined) { expect_right(1004, 119, {"slip_zone"}); }

TEST(DiagnosisBenchmarkRun, TinyRunWritesConsistentFiles) {
  testing_support::TempDir dir;
  DiagnosisBenchmarkRequest r;
  r.out = (dir.path() / "bench").string();
  r.keep_tracks = true;
  r.options.cases = 2;
  r.options.seed = 1002;  // a development seed
  r.options.threads = 2;
  r.options.draw = short_draws();
  r.options.draw.max_minutes = 0.6;
  const StudyRun run = run_diagnosis_benchmark_to_folder(r);
  for (const char* f : {"cases.csv", "confusion.csv", "confusion.png", "confusion.svg", "summary.md"})
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(r.out) / f)) << f;
  EXPECT_EQ(run.files.size(), 5u);
  for (int i = 0; i < 2; ++i)
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(r.out) / "tracks" /
                                        (std::string("case_000") + std::to_string(i) + ".csv")));
  // cases.csv: a header and one row per case, each with the case's seed.
  const std::string csv = read_file(std::filesystem::path(r.out) / "cases.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);
  for (int i = 0; i < 2; ++i)
    EXPECT_NE(csv.find("\n" + std::to_string(i) + "," + std::to_string(case_seed(1002, i)) + ","),
              std::string::npos);
  // confusion.csv: 13 rows of 14 counts under a header; at least one count per case.
  std::istringstream conf(read_file(std::filesystem::path(r.out) / "confusion.csv"));
  std::string line;
  std::getline(conf, line);
  EXPECT_EQ(std::count(line.begin(), line.end(), ','), 14);
  int rows = 0, total = 0;
  while (std::getline(conf, line)) {
    ++rows;
    std::istringstream cells(line);
    std::string cell;
    std::getline(cells, cell, ',');
    while (std::getline(cells, cell, ',')) total += std::stoi(cell);
  }
  EXPECT_EQ(rows, 13);
  EXPECT_GE(total, 2);
  const std::string md = read_file(std::filesystem::path(r.out) / "summary.md");
  EXPECT_NE(md.find("## Against the aims"), std::string::npos);
  for (const char* row : {"| single effect, 3 floors or more |", "| two effects, 3 floors or more |",
                          "| single effect, 1.5-3 floors |", "| two effects, 1.5-3 floors |",
                          "| single effect, under 1.5 floors |", "| null cases with any finding |"})
    EXPECT_NE(md.find(row), std::string::npos) << row;
  EXPECT_NE(md.find(">= 97 %"), std::string::npos);
  EXPECT_NE(md.find("<= 2 %"), std::string::npos);
  EXPECT_NE(md.find("seed 1002"), std::string::npos);
  // The margin table counts every graded case but the undetectable ones once.
  const auto at = md.find("## By margin");
  ASSERT_NE(at, std::string::npos);
  const std::string part = md.substr(at, md.find("## By reference shape") - at);
  const std::regex row(R"(\| (null|single|two)[^|]* \| (\d+)/(\d+) \()");
  int in_margin = 0;
  for (auto it = std::sregex_iterator(part.begin(), part.end(), row); it != std::sregex_iterator(); ++it)
    in_margin += std::stoi((*it)[3].str());
  EXPECT_GE(in_margin, 1);
  EXPECT_LE(in_margin, 2);
}

TEST(DiagnosisBenchmarkRun, BadOptionsFailBeforeWork) {
  DiagnosisBenchmarkOptions o;
  std::string why;
  o.cases = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("cases"), std::string::npos);
  o.cases = 1;
  o.draw.max_minutes = 0.1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("max_minutes"), std::string::npos);
  o.draw = {};
  o.draw.null_share = 0.8, o.draw.two_share = 0.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("two_share"), std::string::npos);
  for (double bad : {-0.1, 1.5, std::nan("")}) {
    o.draw = {};
    o.draw.multi_share = bad;
    EXPECT_FALSE(o.IsValid(&why));
    EXPECT_NE(why.find("multi_share"), std::string::npos) << why;
  }
  {
    testing_support::TempDir d;
    DiagnosisBenchmarkRequest r;
    r.out = (d.path() / "out").string();
    r.options.draw.multi_share = 2.0;
    try {
      run_diagnosis_benchmark_to_folder(r);
      ADD_FAILURE() << "--multi-share 2 was accepted";
    } catch (const core::Failure& e) {
      EXPECT_NE(std::string(e.what()).find("multi_share = 2"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(r.out));
  }
  o.draw = {};
  o.draw.null_share = 0.8, o.draw.two_share = 0.5;
  // The command's library call: one line, before any work, nothing written.
  testing_support::TempDir dir;
  DiagnosisBenchmarkRequest r;
  r.out = (dir.path() / "out").string();
  r.options = o;
  EXPECT_THROW(run_diagnosis_benchmark_to_folder(r), core::Failure);
  EXPECT_FALSE(std::filesystem::exists(r.out));
  r.options = {};
  r.out = (dir.path() / "file.txt").string();
  std::ofstream(r.out) << "x";
  try {
    run_diagnosis_benchmark_to_folder(r);
    ADD_FAILURE() << "an --out that is a file was accepted";
  } catch (const core::Failure& e) {
    EXPECT_NE(std::string(e.what()).find("not a folder"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------- multi-recording cases

CaseDrawOptions multi_draws() {
  CaseDrawOptions o = short_draws();
  o.multi_share = 1.0;
  return o;
}

TEST(DiagnosisMultiCases, OneRobotSameEffectsOwnDrives) {
  const CaseDrawOptions o = multi_draws();
  CaseDrawOptions single = o;
  single.multi_share = 0.0;
  std::set<std::size_t> counts;
  for (int i = 0; i < 40; ++i) {
    const DiagnosisCase c = draw_case(case_seed(5, i), i, o);
    SCOPED_TRACE("case " + std::to_string(i) + ": " + c.effects_text());
    ASSERT_TRUE(c.multi());
    const std::size_t n = c.recordings.size();
    counts.insert(n);
    ASSERT_GE(n, 2u);
    ASSERT_LE(n, 4u);
    // The held-out recordings are the last one (two of four).
    const int held = n == 4 ? 2 : 1;
    EXPECT_EQ(c.heldout_recordings(), held);
    for (std::size_t k = 0; k < n; ++k) EXPECT_EQ(c.recordings[k].heldout, k + held >= n) << k;
    // The robot, sensors and reference of the single-recording draw.
    const DiagnosisCase one = draw_case(case_seed(5, i), i, single);
    EXPECT_FALSE(one.multi());
    EXPECT_EQ(c.robot, one.robot);
    EXPECT_EQ(c.reference, one.reference);
    EXPECT_EQ(c.odometry, one.odometry);
    EXPECT_EQ(c.gyro_rate_hz, one.gyro_rate_hz);
    const std::string effects = sim::format_effects(c.scenario.effects);
    std::set<std::uint64_t> seeds;
    std::set<double> starts;
    for (const CaseRecording& r : c.recordings) {
      // Same effects and parameters, own seed, start pose and drive length.
      EXPECT_EQ(sim::format_effects(r.scenario.effects), effects);
      seeds.insert(r.seed);
      starts.insert(r.scenario.motion.start_x_m);
      EXPECT_EQ(r.scenario.seed, r.seed);
      EXPECT_GE(sim::MotionProfile(r.scenario.motion).duration_s(), r.duration_s);
      EXPECT_GE(r.duration_s, 30.0);
      EXPECT_LE(r.duration_s, 60.0);
      // Geometry jitter far below detectability; noise within exp(+-0.3).
      for (double f : {r.radius_factor_l, r.radius_factor_r}) EXPECT_LT(std::abs(f - 1.0), 6e-4);
      EXPECT_LT(std::abs(r.base_factor - 1.0), 2e-3);
      EXPECT_NE(r.radius_factor_l, 1.0);
      EXPECT_NEAR(r.scenario.robot.wheel_base_m, c.scenario.robot.wheel_base_m * r.base_factor, 1e-12);
      EXPECT_GE(r.noise_factor, std::exp(-0.3));
      EXPECT_LE(r.noise_factor, std::exp(0.3));
      EXPECT_NEAR(r.scenario.sensors.gyro.sigma_rad_s, c.scenario.sensors.gyro.sigma_rad_s * r.noise_factor,
                  1e-15);
      if (c.reference == BenchReference::gt_gaps) {
        EXPECT_FALSE(r.gt_gaps_s.empty());
      }
    }
    EXPECT_EQ(seeds.size(), n);
    EXPECT_EQ(starts.size(), n);
    for (const TrueEffect& e : c.effects) {
      EXPECT_NE(e.effect, diagnose::Effect::slip_zone);
      EXPECT_NE(e.effect, diagnose::Effect::radius_step);
    }
  }
  EXPECT_EQ(counts, (std::set<std::size_t>{2, 3, 4}));
  // multi_share = 0.25: some cases are multi-recording, the others are the
  // single-recording draws they would be with multi_share = 0.
  CaseDrawOptions quarter = o;
  quarter.multi_share = 0.25;
  int multi = 0;
  for (int i = 0; i < 40; ++i) {
    const DiagnosisCase c = draw_case(case_seed(5, i), i, quarter);
    multi += c.multi() ? 1 : 0;
    if (!c.multi()) {
      EXPECT_EQ(c.effects_text(), draw_case(case_seed(5, i), i, single).effects_text());
    }
  }
  EXPECT_GT(multi, 2);
  EXPECT_LT(multi, 25);
}

TEST(DiagnosisMultiCases, RecordingsAreOfOneRobotAndDeterministic) {
  const CaseDrawOptions o = multi_draws();
  constexpr int kCases = 3;
  std::vector<tracks::Track> tracks[2];
  for (int run = 0; run < 2; ++run) {
    std::vector<std::vector<tracks::Track>> per_case(kCases);
#pragma omp parallel for schedule(dynamic, 1) num_threads(run == 0 ? 1 : 2)
    for (int i = 0; i < kCases; ++i) {
      const DiagnosisCase c = draw_case(case_seed(9, i), i, o);
      for (std::size_t k = 0; k < c.recordings.size(); ++k)
        per_case[static_cast<std::size_t>(i)].push_back(make_recording_track(c, k).track);
    }
    for (auto& v : per_case) tracks[run].insert(tracks[run].end(), v.begin(), v.end());
  }
  ASSERT_EQ(tracks[0].size(), tracks[1].size());
  for (std::size_t k = 0; k < tracks[0].size(); ++k) EXPECT_TRUE(same_track(tracks[0][k], tracks[1][k])) << k;

  for (int i = 0; i < kCases; ++i) {
    const DiagnosisCase c = draw_case(case_seed(9, i), i, o);
    SCOPED_TRACE("case " + std::to_string(i));
    EXPECT_THROW(make_case_track(c), std::invalid_argument);
    EXPECT_THROW(make_recording_track(c, c.recordings.size()), std::invalid_argument);
    std::vector<diagnose::DiagInput> inputs;
    for (std::size_t k = 0; k < c.recordings.size(); ++k) {
      const tracks::Track t = make_recording_track(c, k).track;
      // The nominal geometry, whatever the recording's true one.
      EXPECT_EQ(t.meta().wheel_radius_left_m, c.scenario.robot.wheel_radius_left_m);
      EXPECT_EQ(t.meta().wheel_base_m, c.scenario.robot.wheel_base_m);
      EXPECT_EQ(t.meta().get("bench.recording"), std::to_string(k + 1));
      inputs.push_back(diagnose::build_diag_input(t));
    }
    ASSERT_GE(inputs.size(), 2u);
    EXPECT_NO_THROW(diagnose::check_one_robot(inputs));
    EXPECT_NE(inputs[0].ref_x_m.front(), inputs[1].ref_x_m.front());  // own start pose
  }
}

// Inputs of the recordings of `c`, held out last.
void multi_inputs(const DiagnosisCase& c, std::vector<diagnose::DiagInput>& fit,
                  std::vector<diagnose::DiagInput>& held) {
  for (std::size_t k = 0; k < c.recordings.size(); ++k)
    (c.recordings[k].heldout ? held : fit)
        .push_back(diagnose::build_diag_input(make_recording_track(c, k).track));
}

TEST(DiagnosisMultiCases, TruthOfALargeEffectIsDetectableAndOfNoneNot) {
  CaseDrawOptions o = multi_draws();
  o.null_share = 1.0, o.two_share = 0.0;
  // A null case on ground truth with ticks.
  DiagnosisCase c;
  for (int i = 0; i < 100; ++i) {
    c = draw_case(case_seed(77, i), i, o);
    if (c.reference == BenchReference::gt_full && c.odometry == BenchOdometry::ticks) break;
  }
  ASSERT_EQ(c.reference, BenchReference::gt_full);
  ASSERT_TRUE(c.effects.empty());
  std::vector<diagnose::DiagInput> fit, held;
  multi_inputs(c, fit, held);
  const Detectability none = assess_recordings_detectability(fit, held, c.effects);
  EXPECT_EQ(none.detectable_count(), 0);
  EXPECT_GT(none.floor_m, 0.0);
  EXPECT_GT(none.windows, 0);
  // The same recordings with a 5 % wider wheel base on every one of them.
  const TrueEffect base = effect("wheel_base_error", {{"scale", 1.05}});
  c.effects = {base};
  for (CaseRecording& r : c.recordings)
    sim::apply_effect(r.scenario.effects, sim::EffectSpec{std::string(base.name()), base.params});
  fit.clear(), held.clear();
  multi_inputs(c, fit, held);
  const Detectability large = assess_recordings_detectability(fit, held, c.effects);
  ASSERT_EQ(large.effects.size(), 1u);
  EXPECT_TRUE(large.effects[0].detectable);
  EXPECT_GT(large.effects[0].gain_m, 3.0 * large.effects[0].floor_m);
  EXPECT_LT(large.true_heldout_m, large.nominal_heldout_m);
  // Judged on the held-out recordings: their nominal error, not the fit ones'.
  double sse = 0.0, n = 0.0;
  for (const diagnose::DiagInput& in : held) {
    const diagnose::ReplayResult r = diagnose::replay(in, diagnose::EffectSet{}, large.window_s);
    for (const diagnose::WindowError& w : r.windows)
      sse += static_cast<double>(w.n_ref) * w.pos_rmse_m * w.pos_rmse_m, n += static_cast<double>(w.n_ref);
  }
  EXPECT_NEAR(large.nominal_heldout_m, std::sqrt(sse / n), 1e-12);
  EXPECT_THROW(assess_recordings_detectability(fit, {}, c.effects), std::invalid_argument);
}

// Every number of two runs but the timings.
std::string run_text(const DiagnosisBenchmark& b) {
  std::string s;
  for (const CaseResult& r : b.cases) {
    s += std::to_string(r.c.index) + "|" + std::to_string(r.c.recordings.size()) + "|" + r.grade.why + "|" +
         (r.grade.pass ? "pass" : "fail") + "|" + std::to_string(r.track_rows);
    for (const CaseFinding& f : r.findings) s += "|" + f.spec + fmt::format("{}", f.heldout_after_m);
    for (const EffectTruth& t : r.truth.effects)
      s += fmt::format("|{}:{}:{}", t.effect.name(), t.gain_m, t.floor_m);
    s += fmt::format("|{}|{}\n", r.grade.heldout_before_m, r.grade.heldout_after_m);
  }
  return s;
}

TEST(DiagnosisMultiCases, ShortRunGradesAndWritesTheirRows) {
  DiagnosisBenchmarkOptions o;
  o.cases = 3;
  o.seed = 1003;  // a development seed
  o.draw = multi_draws();
  o.draw.max_minutes = 0.6;
  o.threads = 1;
  const DiagnosisBenchmark one = run_diagnosis_benchmark(o);
  o.threads = 2;
  const DiagnosisBenchmark two = run_diagnosis_benchmark(o);
  EXPECT_EQ(run_text(one), run_text(two));
  const CategoryRates& m = one.summary.multi_recording;
  EXPECT_EQ(m.null_cases.cases + m.undetectable.cases + m.single.cases + m.two.cases, 3);
  const CategoryRates& s = one.summary.single_recording;
  EXPECT_EQ(s.null_cases.cases + s.undetectable.cases + s.single.cases + s.two.cases, 0);
  for (const CaseResult& r : one.cases) {
    EXPECT_TRUE(r.c.multi());
    EXPECT_FALSE(r.grade.refused && r.c.reference != BenchReference::start_fixes) << r.grade.why;
    EXPECT_GT(r.truth.windows, 0) << r.truth_note;
  }

  testing_support::TempDir dir;
  DiagnosisBenchmarkRequest req;
  req.out = (dir.path() / "bench").string();
  req.keep_tracks = true;
  req.options = o;
  run_diagnosis_benchmark_to_folder(req);
  const std::filesystem::path out(req.out);
  for (const CaseResult& r : one.cases)
    for (std::size_t k = 1; k <= r.c.recordings.size(); ++k)
      EXPECT_TRUE(std::filesystem::exists(out / "tracks" / fmt::format("case_{:04d}_r{}.csv", r.c.index, k)));
  EXPECT_FALSE(std::filesystem::exists(out / "tracks" / "case_0000.csv"));
  const std::string md = read_file(out / "summary.md");
  for (const char* row :
       {"| multi-recording: single effect, 3 floors or more |",
        "| multi-recording: two effects, 1.5-3 floors |", "| multi-recording: null cases with any finding |"})
    EXPECT_NE(md.find(row), std::string::npos) << row;
  const std::string csv = read_file(out / "cases.csv");
  EXPECT_EQ(csv.rfind("case,case_seed,category,recordings,heldout_recordings,", 0), 0u);
  for (const CaseResult& r : one.cases)
    EXPECT_NE(csv.find(fmt::format("\n{},{},{},{},{},", r.c.index, r.c.seed, to_string(r.grade.category),
                                   r.c.recordings.size(), r.c.heldout_recordings())),
              std::string::npos);
}

}  // namespace
}  // namespace odotune::studies

// The term search (odotune/diagnose/term_search.h): a planted out-of-round wheel is
// recovered as its two harmonic terms, a clean track gives none, and
// diagnose() reports the terms as the `model` of an unexplained finding.
#include <odotune/diagnose/term_search.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/diagnose/diagnosis.h>
#include <odotune/diagnose/diagnosis_summary.h>
#include <odotune/diagnose/materiality.h>
#include <odotune/diagnose/recordings.h>
#include <odotune/diagnose/window_replay.h>

#include "diagnose/sim_track.h"

namespace odotune::diagnose {
namespace {

using sim::TermBasis;
using sim::TermTarget;

constexpr double kAmp = 0.01, kPhase = 0.4;  // radius ±1 % once per turn

// A 90 s drive of sim_track.h's circuit by a robot with 0.15 m wheels,
// ground truth at 50 Hz (1 mm), with `terms` planted.
tracks::Track track_with_terms(const std::vector<sim::ModelTerm>& terms, std::uint64_t seed) {
  testing_support::SimTrackOptions o;
  o.duration_s = 90.0, o.seed = seed;
  o.wheel_radius_left_m = o.wheel_radius_right_m = 0.15;
  o.wheel_base_m = 0.45, o.ticks_per_rev = 4096;
  o.odo_rate_hz = o.gt_rate_hz = o.gyro_rate_hz = 50.0;
  o.gt_sigma_m = 0.001;
  sim::Scenario sc = testing_support::sim_scenario(o);
  sc.terms = terms;
  return sim::simulate(sc);
}

// The same drive, the left wheel out of round when asked.
tracks::Track out_of_round_track(bool planted, std::uint64_t seed) {
  if (!planted) return track_with_terms({}, seed);
  return track_with_terms({{TermTarget::v_l, TermBasis::sin_1, kAmp * std::cos(kPhase)},
                           {TermTarget::v_l, TermBasis::cos_1, kAmp * std::sin(kPhase)}},
                          seed);
}

struct Split {
  std::vector<Window> windows;
  std::vector<int> train, heldout;
};
Split split(const DiagInput& in) {
  Split s{make_windows(in, 20.0), {}, {}};
  const int n = static_cast<int>(s.windows.size());
  for (int i = 0; i < n; ++i)
    (i < n - static_cast<int>(std::round(0.3 * n)) ? s.train : s.heldout).push_back(i);
  return s;
}

TermSearchResult search(const DiagInput& in, const Split& s) {
  const double nominal = replay(in, EffectSet{}, 20.0, s.heldout).pos_rmse_m;
  return search_terms(in, EffectSet{}, s.windows, s.train, s.heldout,
                      materiality_floor_m(in.ref_sigma_m, nominal));
}

const FoundTerm* term(const TermModel& m, TermBasis b) {
  for (const FoundTerm& t : m.terms)
    if (t.term.target == TermTarget::v_l && t.term.basis == b) return &t;
  return nullptr;
}

TEST(TermSearch, RecoversAPlantedOutOfRoundWheel) {
  const DiagInput in = build_diag_input(out_of_round_track(true, 5));
  const Split s = split(in);
  const TermSearchResult r = search(in, s);
  ASSERT_TRUE(r.found) << r.reason;
  EXPECT_EQ(r.library_size, 45);  // 15 bases on each wheel, and on both with one coefficient
  EXPECT_EQ(r.model.terms.size(), 2u) << r.model.formula;
  const FoundTerm* sn = term(r.model, TermBasis::sin_1);
  const FoundTerm* cs = term(r.model, TermBasis::cos_1);
  ASSERT_TRUE(sn && cs) << r.model.formula;
  EXPECT_EQ(sn->name, "v_l·sin(φ_l)");
  EXPECT_NEAR(sn->term.coef, kAmp * std::cos(kPhase), 0.25 * kAmp * std::cos(kPhase));
  EXPECT_NEAR(cs->term.coef, kAmp * std::sin(kPhase), 0.25 * kAmp * std::sin(kPhase));
  EXPECT_NEAR(std::hypot(sn->term.coef, cs->term.coef), kAmp, 0.25 * kAmp);
  EXPECT_GT(sn->std_error, 0.0);
  EXPECT_LT(sn->std_error, 0.1 * kAmp);
  EXPECT_THAT(r.model.formula, ::testing::StartsWith("v_l,true = v_l·(1 + 0.0"));
  EXPECT_THAT(r.model.conditions, ::testing::HasSubstr("left wheel's angle, once per turn"));
  EXPECT_LT(r.model.heldout.after_pos_rmse_m, r.model.heldout.before_pos_rmse_m - r.floor_m);
  EXPECT_LT(r.model.train.after_pos_rmse_m, r.model.train.before_pos_rmse_m);
}

// Both wheels slowed alike in turns taken at speed: the terms come out on
// both wheels with one coefficient, not on one wheel (which would claim the
// wheels differ).
TEST(TermSearch, ATermOfBothWheelsIsNotPinnedOnOne) {
  constexpr double kCoef = -0.08;
  const DiagInput in = build_diag_input(track_with_terms(
      {{TermTarget::v_l, TermBasis::turn_speed, kCoef}, {TermTarget::v_r, TermBasis::turn_speed, kCoef}}, 11));
  const TermSearchResult r = search(in, split(in));
  ASSERT_TRUE(r.found) << r.reason;
  ASSERT_GE(r.model.terms.size(), 2u) << r.model.formula;
  const FoundTerm& a = r.model.terms[0];
  const FoundTerm& b = r.model.terms[1];
  EXPECT_EQ(a.term.basis, TermBasis::turn_speed) << r.model.formula;
  EXPECT_EQ(a.term.target, TermTarget::v_l) << r.model.formula;
  EXPECT_EQ(b.term.target, TermTarget::v_r) << r.model.formula;
  EXPECT_EQ(a.term.coef, b.term.coef);
  EXPECT_NEAR(a.term.coef, kCoef, 0.25 * std::abs(kCoef));
  EXPECT_THAT(r.model.formula, ::testing::HasSubstr("v_r,true"));
}

TEST(TermSearch, FindsNothingOnACleanTrack) {
  const DiagInput in = build_diag_input(out_of_round_track(false, 5));
  const TermSearchResult r = search(in, split(in));
  EXPECT_FALSE(r.found) << r.model.formula;
  EXPECT_FALSE(r.reason.empty());
  ASSERT_FALSE(r.steps.empty());
  EXPECT_TRUE(r.steps.front().accepted);  // the empty support, scored
}

TEST(TermSearch, DiagnoseReportsTheTermsOnAnUnexplainedFinding) {
  const Diagnosis d = diagnose(build_diag_input(out_of_round_track(true, 7)));
  ASSERT_TRUE(d.term_search.found) << d.term_search.reason;
  const Finding* u = nullptr;
  for (const Finding& f : d.findings)
    if (f.is_unexplained()) u = &f;
  ASSERT_NE(u, nullptr);
  ASSERT_TRUE(u->model.has_value());
  const FoundTerm* sn = term(*u->model, TermBasis::sin_1);
  ASSERT_NE(sn, nullptr) << u->model->formula;
  EXPECT_NEAR(sn->term.coef, kAmp * std::cos(kPhase), 0.25 * kAmp * std::cos(kPhase));
  EXPECT_LT(u->model->heldout.after_pos_rmse_m, u->model->heldout.before_pos_rmse_m);
  EXPECT_TRUE(u->spec().empty());  // not an effect of the list

  DiagnoseOptions off;
  off.terms.enabled = false;
  const Diagnosis without = diagnose(build_diag_input(out_of_round_track(true, 7)), off);
  for (const Finding& f : without.findings) EXPECT_FALSE(f.model.has_value());
  EXPECT_FALSE(without.term_search.found);
}

TEST(TermSearch, RejectsBadOptionsAndWindows) {
  TermSearchOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why));
  o.max_terms = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, ::testing::HasSubstr("max_terms"));
  const DiagInput in = build_diag_input(out_of_round_track(false, 3));
  const Split s = split(in);
  EXPECT_THROW(search_terms(in, EffectSet{}, s.windows, {}, s.heldout, 0.0), std::invalid_argument);
  EXPECT_THROW(search_terms(in, EffectSet{}, s.windows, {0, 99}, s.heldout, 0.0), std::invalid_argument);
  EXPECT_THROW(search_terms(in, EffectSet{}, s.windows, s.train, s.heldout, 0.0, o), std::invalid_argument);
}

// A term model found on one recording is proven elsewhere only where it
// holds: replayed on another recording of the out-of-round robot it lowers
// the error, on a recording with round wheels it does not, and the pooled
// diagnosis then keeps the formula out of its first line.
TEST(TermSearch, TermsAreProvenOnlyOnRecordingsWhereTheyHold) {
  const DiagInput planted = build_diag_input(out_of_round_track(true, 7));
  const Split s = split(planted);
  const TermSearchResult r = search(planted, s);
  ASSERT_TRUE(r.found) << r.reason;
  std::vector<sim::ModelTerm> terms;
  for (const FoundTerm& t : r.model.terms) terms.push_back(t.term);
  const TermScore same = replay_terms(build_diag_input(out_of_round_track(true, 8)), EffectSet{}, terms, 20.0);
  EXPECT_LT(same.after_pos_rmse_m, 0.7 * same.before_pos_rmse_m);
  EXPECT_GT(same.samples, 1000u);
  const TermScore round = replay_terms(build_diag_input(out_of_round_track(false, 8)), EffectSet{}, terms,
                                       20.0);
  EXPECT_GE(round.after_pos_rmse_m, round.before_pos_rmse_m);

  const DiagInput other = build_diag_input(out_of_round_track(false, 9));
  const PooledDiagnosis p = diagnose_recordings({planted}, {other});
  const Finding* u = nullptr;
  for (const Finding& f : p.pooled.findings)
    if (f.model) u = &f;
  ASSERT_NE(u, nullptr);
  EXPECT_FALSE(u->model->proven);
  ASSERT_TRUE(u->model->other_recordings.has_value());
  const std::vector<std::string> lines = pooled_summary(p);
  EXPECT_EQ(lines.front().find(u->model->formula), std::string::npos) << lines.front();
  EXPECT_NE(lines.front().find("not proven"), std::string::npos) << lines.front();
}

}  // namespace
}  // namespace odotune::diagnose

// robot_localization's EKF on a track (odotune/objectives/rl_track.h): where it
// starts, what it is scored by against ground truth, the refusals, and
// several tracks tuned as one objective (RlObjective over recordings).
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/objectives/rl_objective.h>
#include <odotune/objectives/rl_track.h>
#include <odotune/rlnode/params.h>

#include "support/rl_team_file.h"
#include "support/synthetic_track.h"
#include "support/temp_dir.h"

namespace {

using namespace odotune;
using testing::HasSubstr;

struct TeamFile {
  testing_support::TempDir dir{"rl-track"};
  rlnode::RlParams params(bool gyro = false) {
    const auto path = dir.path() / (gyro ? "gyro.yaml" : "user.yaml");
    std::ofstream(path) << testing_support::kRlTeamFile << (gyro ? testing_support::kRlGyroInput : "");
    return rlnode::read_rl_params(path);
  }
};

objectives::RlTrackOptions sigma(double s) {
  objectives::RlTrackOptions o;
  o.fix_sigma_m = s;
  return o;
}

objectives::RlTuneOptions short_protocols() {
  objectives::RlTuneOptions o;
  o.outage_s = {10.0};
  o.outage_stride_s = 5.0;
  o.warmup_s = 10.0;
  return o;
}

std::string refusal(const tracks::Track& track, const rlnode::RlParams& p,
                    const objectives::RlTrackOptions& o) {
  try {
    objectives::load_rl_track(track, "drive.csv", p, o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(RlTrack, StartsAtTheFirstFixWithTheFittedHeadingAndFollowsTheTruth) {
  TeamFile f;
  const tracks::Track track = testing_support::synthetic_track(1);
  const objectives::RlTrack t = objectives::load_rl_track(track, "drive.csv", f.params(true), sigma(0.06));
  EXPECT_EQ(t.odometry, tracks::OdometryInput::wheels);
  EXPECT_EQ(t.rec.start_ns, 1'000'000'000);  // the first fix, at 1 s
  ASSERT_TRUE(t.rec.params.initial_state.has_value());
  EXPECT_NEAR((*t.rec.params.initial_state)[filters::rl::kX], track.col(tracks::Col::aps_x)[50], 1e-12);
  EXPECT_LT(std::abs(t.initial_heading_error_rad), 0.15);  // fitted on 5 m of a wheel-biased path
  EXPECT_THAT(t.start_note, HasSubstr("start at the first fix"));
  const objectives::RlTrackScores s = objectives::score_rl_track(t, rlnode::settings_of(t.rec.params),
                                                                 short_protocols());
  EXPECT_TRUE(s.run.finite);
  EXPECT_GT(s.run.samples, 1000);
  EXPECT_LT(s.run.rmse_m, 0.15);
  // Without fixes the 1 % wheel error grows: the outages are worse than the fused run.
  EXPECT_GT(s.windows, 5u);
  EXPECT_GT(s.outages.rmse_m, s.run.rmse_m);
  EXPECT_GT(s.heldout_fixes.fixes, 50);
  EXPECT_GT(s.outage_fixes.fixes, 0);
}

TEST(RlTrack, TruthScoreInterpolatesAndSkipsWhereThereIsNoTruth) {
  const std::vector<objectives::TruthSample> truth = {
      {0, 0.0, 0.0}, {1'000'000'000, 1.0, 0.0}, {2'000'000'000, 2.0, 0.0}};
  std::vector<rlnode::TrajectoryPoint> path(3);
  path[0].time_ns = 500'000'000;
  path[0].state[filters::rl::kX] = 0.5;  // on the truth
  path[1].time_ns = 1'500'000'000;
  path[1].state[filters::rl::kX] = 1.5;
  path[1].state[filters::rl::kY] = 1.0;  // 1 m off
  path[2].time_ns = 5'000'000'000;       // after the truth: not scored
  path[2].state[filters::rl::kX] = 9.0;
  const objectives::TruthScore s = objectives::truth_score(truth, path);
  EXPECT_EQ(s.samples, 2);
  EXPECT_NEAR(s.rmse_m, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(s.max_m, 1.0, 1e-12);
  EXPECT_EQ(objectives::truth_score(truth, path, 1'000'000'000).samples, 1);
  const std::vector<objectives::TruthScore> both = {s, objectives::truth_score(truth, path, 1'000'000'000)};
  EXPECT_EQ(objectives::pooled(std::span<const objectives::TruthScore>(both)).samples, 3);
  EXPECT_NEAR(objectives::pooled(std::span<const objectives::TruthScore>(both)).rmse_m, std::sqrt(2.0 / 3.0),
              1e-12);
}

TEST(RlTrack, ATrackWithoutWhatTheFileFusesIsRefusedInOneLine) {
  TeamFile f;
  const tracks::Track track = testing_support::synthetic_track(2);
  EXPECT_THAT(refusal(track, f.params(), objectives::RlTrackOptions{}),
              AllOf(HasSubstr("drive.csv"), HasSubstr("no variances"), HasSubstr("--fix-sigma-m")));
  tracks::TrackData no_gyro = track.data();
  no_gyro.col(tracks::Col::gyro_z).clear();
  EXPECT_THAT(refusal(tracks::Track(no_gyro), f.params(true), sigma(0.06)),
              AllOf(HasSubstr("imu0"), HasSubstr("gyro_z")));
  tracks::TrackData no_fixes = track.data();
  no_fixes.col(tracks::Col::aps_x).clear();
  no_fixes.col(tracks::Col::aps_y).clear();
  EXPECT_THAT(refusal(tracks::Track(no_fixes), f.params(), sigma(0.06)),
              AllOf(HasSubstr("odom1"), HasSubstr("aps_x")));
  objectives::RlTrackOptions bad = sigma(0.06);
  bad.odometry_var_vx = -1.0;
  EXPECT_THAT(refusal(track, f.params(), bad), HasSubstr("variance"));
  const std::string line = refusal(tracks::Track(no_gyro), f.params(true), sigma(0.06));
  EXPECT_EQ(line.find('\n'), std::string::npos);
}

TEST(RlTrack, SeveralTracksPoolTheirFixesInOneObjective) {
  TeamFile f;
  const rlnode::RlParams p = f.params(true);
  const objectives::RlTrack a = objectives::load_rl_track(testing_support::synthetic_track(3), "a.csv", p,
                                                          sigma(0.06));
  const objectives::RlTrack b = objectives::load_rl_track(testing_support::synthetic_track(4, 50.0), "b.csv", p,
                                                          sigma(0.06));
  const objectives::RlTuneOptions o = short_protocols();
  const rlnode::ReplaySettings base = rlnode::settings_of(p);
  const objectives::RlObjective one_a(a.rec, base, o), one_b(b.rec, base, o);
  const std::vector<const rlnode::Recording*> recs = {&a.rec, &b.rec};
  const objectives::RlObjective joint(recs, base, o);
  const objectives::FixScore ha = one_a.baseline_heldout(), hb = one_b.baseline_heldout(),
                             h = joint.baseline_heldout();
  EXPECT_EQ(h.fixes, ha.fixes + hb.fixes);
  const double n = static_cast<double>(h.fixes);
  EXPECT_NEAR(h.rmse_m,
              std::sqrt((ha.rmse_m * ha.rmse_m * static_cast<double>(ha.fixes) +
                         hb.rmse_m * hb.rmse_m * static_cast<double>(hb.fixes)) /
                        n),
              1e-12);
  EXPECT_EQ(joint.window_count(), one_a.window_count() + one_b.window_count());
  // The lock-step batch is the single calls, bit for bit.
  const auto [lo, hi] = joint.bounds();
  std::vector<double> xs;
  for (int k = 0; k < 3; ++k)
    for (std::size_t i = 0; i < lo.size(); ++i) xs.push_back(lo[i] + (hi[i] - lo[i]) * (0.3 + 0.2 * k));
  std::vector<double> batch(3);
  joint.fitness_batch(xs, batch);
  for (std::size_t k = 0; k < 3; ++k)
    EXPECT_EQ(batch[k], joint.fitness(std::span<const double>(xs).subspan(k * lo.size(), lo.size())));
  // The innovation statistics take one recording.
  objectives::RlTuneOptions nis = o;
  nis.fitness = objectives::RlFitness::nis;
  EXPECT_THROW(objectives::RlObjective(recs, base, nis), std::invalid_argument);
}

TEST(RlTrack, TheFixesOwnVarianceCanBeTakenOutOfTheScores) {
  objectives::FixScore hand;
  hand.rmse_m = 1.5;
  hand.fix_var_m2 = 2.0;
  EXPECT_NEAR(objectives::error_without_fix_noise_m(hand), 0.5, 1e-12);
  hand.rmse_m = 1.0;  // noisier than the residuals: no error left, not a NaN
  EXPECT_EQ(objectives::error_without_fix_noise_m(hand), 0.0);

  TeamFile f;
  const rlnode::RlParams p = f.params(true);
  const objectives::RlTrack a = objectives::load_rl_track(testing_support::synthetic_track(3), "a.csv", p,
                                                          sigma(0.06));
  const objectives::RlTrack b = objectives::load_rl_track(testing_support::synthetic_track(4, 50.0), "b.csv", p,
                                                          sigma(0.06));
  const std::vector<const rlnode::Recording*> recs = {&a.rec, &b.rec};
  const rlnode::ReplaySettings base = rlnode::settings_of(p);
  objectives::RlTuneOptions o = short_protocols();
  const objectives::RlObjective plain(recs, base, o);
  o.subtract_fix_variance = true;
  o.keep_heldout = false;  // the parts alone, without the guard's ranking
  const objectives::RlObjective without_noise(recs, base, o);
  // Every scored fix carries var_x + var_y = 2 σ².
  EXPECT_NEAR(plain.baseline_heldout().fix_var_m2, 2 * 0.06 * 0.06, 1e-12);
  EXPECT_NEAR(plain.baseline_outage().fix_var_m2, 2 * 0.06 * 0.06, 1e-12);
  // The file's own values score 1 + 1 either way; elsewhere the parts are
  // the errors without the fixes' noise, each relative to the file's.
  const std::vector<double> at_file(plain.bounds().first.size(), 0.0);
  EXPECT_NEAR(without_noise.data_fitness(at_file), 2.0, 1e-12);
  std::vector<double> x = at_file;
  x[0] = 1.0;
  const rlnode::ReplaySettings s = without_noise.settings_at(x);
  const double expected = objectives::error_without_fix_noise_m(without_noise.heldout_score(s)) /
                              objectives::error_without_fix_noise_m(without_noise.baseline_heldout()) +
                          objectives::error_without_fix_noise_m(without_noise.outage_score(s)) /
                              objectives::error_without_fix_noise_m(without_noise.baseline_outage());
  const double scored = without_noise.data_fitness(x);
  EXPECT_NEAR(scored, expected, 1e-12);
  EXPECT_NE(scored, plain.data_fitness(x));
  // Variances far above the fixes' scatter leave no error to score: refused.
  const objectives::RlTrack loud = objectives::load_rl_track(testing_support::synthetic_track(3), "loud.csv", p,
                                                             sigma(10.0));
  try {
    objectives::RlObjective(loud.rec, base, o);
    ADD_FAILURE() << "not refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("exceed the file's squared error"));
    EXPECT_THAT(e.what(), HasSubstr("--subtract-fix-variance"));
  }
}

// Which fixes robot_localization's replay fuses, withholds and scores
// (odotune/objectives/rl_protocols.h), and the outage windows replayed from one fused
// run (OutageReplays) against each window replayed on its own, on a small
// synthetic GPS drive (tests/support/rl_gps_bag.h: 80 s, fixes at 2 Hz).
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include <odotune/objectives/rl_bag_scores.h>
#include <odotune/objectives/rl_objective.h>
#include <odotune/objectives/rl_protocols.h>
#include <odotune/rlnode/gps_alignment.h>
#include <odotune/rlnode/params.h>

#include "support/rl_gps_bag.h"
#include "support/temp_dir.h"

namespace {

using namespace odotune;
using rlnode::FixRole;

constexpr std::int64_t kSecond = 1'000'000'000;

struct ProtocolDrive {
  testing_support::TempDir dir{"rl-protocols"};
  rlnode::Recording rec;
  ProtocolDrive() {
    const auto params = dir.path() / "p.yaml";
    std::ofstream(params) << testing_support::kRlGpsParams;
    rec = rlnode::load_recording(testing_support::rl_gps_bag(dir.path(), 0.4), rlnode::read_rl_params(params));
    rec.gps_transform = rlnode::fit_gps_alignment(rec, rlnode::settings_of(rec.params), 30.0).transform;
  }
  std::int64_t t0() const { return rec.fixes.front().stamp_ns; }
};

}  // namespace

TEST(RlProtocols, OutageWindowsStartEveryStrideAfterTheWarmUpAndEndInTheSpan) {
  ProtocolDrive d;
  const std::vector<double> lengths = {10.0, 20.0};
  const std::int64_t until = d.t0() + 60 * kSecond;
  const std::vector<objectives::OutageWindow> w = objectives::outage_windows(
      d.rec, lengths, 5.0, objectives::after_warmup(d.rec, 15.0), until);
  // Starts at 15, 20, … s: 10-s windows up to a start of 50 s, 20-s ones up to 40 s.
  ASSERT_EQ(w.size(), 8u + 6u);
  int ten = 0, twenty = 0;
  for (std::size_t k = 0; k < w.size(); ++k) {
    const std::int64_t since = w[k].start_ns - d.t0();
    EXPECT_GE(since, 15 * kSecond);
    EXPECT_EQ(since % (5 * kSecond), 0);
    EXPECT_LE(w[k].end_ns, until);
    if (k > 0) {
      EXPECT_GE(w[k].start_ns, w[k - 1].start_ns);
    }
    const std::int64_t length = w[k].end_ns - w[k].start_ns;
    ten += length == 10 * kSecond;
    twenty += length == 20 * kSecond;
  }
  EXPECT_EQ(ten, 8);
  EXPECT_EQ(twenty, 6);
  EXPECT_TRUE(
      objectives::outage_windows(d.rec, lengths, 5.0, objectives::after_warmup(d.rec, 55.0), until).empty());
}

TEST(RlProtocols, RolesFuseBeforeScoreInsideAndLeaveOutAfter) {
  ProtocolDrive d;
  const objectives::OutageWindow w{d.t0() + 20 * kSecond, d.t0() + 30 * kSecond};
  const std::vector<FixRole> roles = objectives::outage_window_roles(d.rec, w);
  const std::vector<FixRole> outage = objectives::outage_protocol_roles(d.rec, w.start_ns, w.end_ns);
  EXPECT_EQ(roles, outage);
  int scored = 0;
  for (std::size_t i = 0; i < roles.size(); ++i) {
    const std::int64_t t = d.rec.fixes[i].stamp_ns;
    const FixRole want = t < w.start_ns ? FixRole::fuse : t < w.end_ns ? FixRole::score : FixRole::absent;
    EXPECT_EQ(roles[i], want) << i;
    scored += roles[i] == FixRole::score;
  }
  EXPECT_EQ(scored, 20);  // 2 Hz for 10 s

  const std::vector<FixRole> fifth = objectives::every_fifth_roles(d.rec, w.start_ns, w.end_ns);
  int k = 0, fifth_scored = 0;
  for (std::size_t i = 0; i < fifth.size(); ++i) {
    const std::int64_t t = d.rec.fixes[i].stamp_ns;
    if (t < w.start_ns) {
      EXPECT_EQ(fifth[i], FixRole::fuse);
    } else if (t >= w.end_ns) {
      EXPECT_EQ(fifth[i], FixRole::absent);
    } else {
      EXPECT_EQ(fifth[i], k++ % 5 == 0 ? FixRole::score : FixRole::fuse) << i;
    }
    fifth_scored += fifth[i] == FixRole::score;
  }
  EXPECT_EQ(fifth_scored, 4);
}

TEST(RlProtocols, EveryFixBeforeTheEndIsHeldOutInExactlyOneFold) {
  ProtocolDrive d;
  const std::int64_t until = d.t0() + 40 * kSecond;
  const auto folds = objectives::heldout_fix_folds(d.rec, 5, 1.0, until);
  ASSERT_EQ(folds.size(), 5u);
  for (std::size_t i = 0; i < d.rec.fixes.size(); ++i) {
    int scored = 0;
    for (const auto& f : folds) scored += f[i] == FixRole::score;
    EXPECT_EQ(scored, d.rec.fixes[i].stamp_ns < until ? 1 : 0) << i;
  }
}

// The windows continue from copies of one fused run: the same scores, bit
// for bit, as each window's own replay from the start.
TEST(RlProtocols, WindowsFromOneFusedRunScoreAsTheirOwnReplays) {
  ProtocolDrive d;
  const std::int64_t until = d.t0() + 70 * kSecond;
  const std::vector<double> lengths = {8.0, 16.0};
  const std::vector<objectives::OutageWindow> windows = objectives::outage_windows(
      d.rec, lengths, 6.0, objectives::after_warmup(d.rec, 10.0), until);
  ASSERT_GT(windows.size(), 10u);
  const objectives::OutageReplays shared(d.rec, windows, until);
  rlnode::ReplaySettings s = rlnode::settings_of(d.rec.params);
  s.process_noise *= 3.0;
  std::vector<rlnode::ReplayOutput> own;
  for (const objectives::OutageWindow& w : windows) {
    own.push_back(rlnode::replay(
        d.rec, rlnode::make_schedule(d.rec, objectives::outage_window_roles(d.rec, w), w.end_ns), s));
  }
  const objectives::FixScore want = objectives::score_of(own), got = shared.score(s);
  EXPECT_GT(want.fixes, 100);
  EXPECT_EQ(got.fixes, want.fixes);
  EXPECT_EQ(got.rmse_m, want.rmse_m);
  EXPECT_EQ(got.mae_m, want.mae_m);
  EXPECT_EQ(got.maxe_m, want.maxe_m);
  EXPECT_TRUE(got.finite);
}

// The eval's one call (odotune/objectives/rl_bag_scores.h): its protocols are
// score_protocols' on [from, until) (30 s of fixes at 2 Hz, every 5th of them),
// its simulated outages start at `from` (without it, after the warm-up) and end
// by `until`, its held-out folds cover the span, every fix is placed under the
// run's transform, and trajectories are kept only when asked (the scores the
// same either way).
TEST(RlProtocols, BagScoresAreTheProtocolsOnTheAskedSpan) {
  ProtocolDrive d;
  rlnode::ReplaySettings s = rlnode::settings_of(d.rec.params);
  s.process_noise *= 3.0;
  objectives::RlBagEvalOptions o;
  o.until_ns = d.t0() + 70 * kSecond;
  o.from_ns = d.t0() + 40 * kSecond;
  o.outage_s = {8.0};
  o.outage_every_s = 6.0;
  const objectives::RlBagScores a = objectives::score_rl_bag(d.rec, s, o);
  ASSERT_TRUE(a.protocols && a.heldout && a.outages);
  const objectives::RlProtocolScores want = objectives::score_protocols(d.rec, s,
                                                                        {*o.from_ns, *o.from_ns, o.until_ns});
  EXPECT_EQ(a.protocols->outage.fixes, 60);
  EXPECT_EQ(a.protocols->every_fifth.fixes, 12);
  EXPECT_EQ(a.protocols->outage.rmse_m, want.outage.rmse_m);
  EXPECT_EQ(a.protocols->every_fifth.rmse_m, want.every_fifth.rmse_m);
  EXPECT_EQ(a.outage_windows, 4u);  // starting at 40, 46, 52 and 58 s
  EXPECT_EQ(a.outages->fixes, 4 * 16);
  EXPECT_GE(a.heldout->fixes, 138);
  EXPECT_LE(a.heldout->fixes, 140);
  ASSERT_EQ(a.fixes.size(), d.rec.fixes.size());
  for (std::size_t i = 0; i < a.fixes.size(); ++i) {
    EXPECT_EQ(a.fixes[i].stamp_ns, d.rec.fixes[i].stamp_ns);
    EXPECT_EQ(a.fixes[i].odom, rlnode::fix_in_odom(d.rec.fixes[i], a.run.gps_transform));
  }
  EXPECT_TRUE(a.run.trajectory.empty());
  EXPECT_TRUE(a.outage_trajectory.empty());

  o.keep_trajectory = true;
  const objectives::RlBagScores b = objectives::score_rl_bag(d.rec, s, o);
  ASSERT_FALSE(b.outage_trajectory.empty());
  EXPECT_FALSE(b.run.trajectory.empty());
  // The same ticks to `until`; after `from` the outage run has no GPS.
  ASSERT_EQ(b.outage_trajectory.size(), b.run.trajectory.size());
  EXPECT_LE(b.outage_trajectory.back().time_ns, o.until_ns);
  EXPECT_NE(b.outage_trajectory.back().state, b.run.trajectory.back().state);
  EXPECT_EQ(b.protocols->outage.rmse_m, a.protocols->outage.rmse_m);
  EXPECT_EQ(b.outages->rmse_m, a.outages->rmse_m);
  EXPECT_EQ(b.heldout->rmse_m, a.heldout->rmse_m);

  o.from_ns.reset();
  const objectives::RlBagScores c = objectives::score_rl_bag(d.rec, s, o);
  EXPECT_FALSE(c.protocols.has_value());
  EXPECT_EQ(c.outage_windows, 6u);  // starting 30 s after the first fix: 30, 36, …, 60 s
}

#include <cmath>

#include <gtest/gtest.h>

#include <odotune/sim/synthetic_fixes.h>

namespace odotune::sim {
namespace {

tracks::Track gt_track(double rate_hz, double duration_s) {
  tracks::TrackData d;
  d.meta.name = "gt";
  const int n = static_cast<int>(duration_s * rate_hz) + 1;
  for (int i = 0; i < n; ++i) {
    const double t = i / rate_hz;
    d.t.push_back(t);
    d.col(tracks::Col::v_cmd).push_back(0.1);
    d.col(tracks::Col::w_cmd).push_back(0.0);
    d.col(tracks::Col::gt_x).push_back(0.1 * t);
    d.col(tracks::Col::gt_y).push_back(-0.2 * t);
  }
  return tracks::Track(std::move(d));
}

TEST(SyntheticFixes, OnePerPeriodWithTheRequestedNoise) {
  const tracks::Track track = gt_track(50.0, 2000.0);
  SyntheticFixOptions o;
  o.rate_hz = 2.0;
  o.sigma_m = 0.06;
  o.seed = 3;
  const tracks::Track out = with_synthetic_fixes(track, o);
  int fixes = 0;
  double sum = 0, sum_sq = 0;
  double last_t = -1;
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!out.at(tracks::Col::aps_x, i)) continue;
    ASSERT_TRUE(out.at(tracks::Col::aps_y, i));
    if (last_t >= 0) {
      EXPECT_NEAR(out.t()[i] - last_t, 0.5, 1e-9);
    }
    last_t = out.t()[i];
    for (double e : {out.col(tracks::Col::aps_x)[i] - out.col(tracks::Col::gt_x)[i],
                     out.col(tracks::Col::aps_y)[i] - out.col(tracks::Col::gt_y)[i]}) {
      sum += e;
      sum_sq += e * e;
    }
    ++fixes;
  }
  EXPECT_EQ(fixes, 4000);  // 2000 s at 2 Hz, none at the start row
  const double m = sum / (2.0 * fixes);
  const double sd = std::sqrt(sum_sq / (2.0 * fixes) - m * m);
  EXPECT_NEAR(m, 0.0, 0.003);
  EXPECT_NEAR(sd, 0.06, 0.003);
  EXPECT_TRUE(out.meta().get("fixes.synthetic").has_value());
}

TEST(SyntheticFixes, EachFixCarriesItsVarianceUnlessAskedNot) {
  const tracks::Track track = gt_track(10.0, 30.0);
  SyntheticFixOptions o;
  o.sigma_m = 0.1;
  const tracks::Track out = with_synthetic_fixes(track, o);
  ASSERT_TRUE(out.has(tracks::Col::aps_var_x) && out.has(tracks::Col::aps_var_y));
  int fixes = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(out.at(tracks::Col::aps_var_x, i), out.at(tracks::Col::aps_x, i));
    if (!out.at(tracks::Col::aps_x, i)) continue;
    EXPECT_DOUBLE_EQ(out.col(tracks::Col::aps_var_x)[i], 0.01);
    EXPECT_DOUBLE_EQ(out.col(tracks::Col::aps_var_y)[i], 0.01);
    ++fixes;
  }
  EXPECT_EQ(fixes, 30);
  // Replaced fixes replace their variances too; without them, none are left.
  o.variances = false;
  const tracks::Track bare = with_synthetic_fixes(out, o);
  EXPECT_FALSE(bare.has(tracks::Col::aps_var_x));
  EXPECT_FALSE(bare.has(tracks::Col::aps_var_y));
  o.variances = true;
  o.sigma_m = 0.0;
  EXPECT_FALSE(with_synthetic_fixes(track, o).has(tracks::Col::aps_var_x));
}

TEST(SyntheticFixes, SeededAndReplacingExistingFixes) {
  const tracks::Track track = gt_track(10.0, 30.0);
  SyntheticFixOptions o;
  o.seed = 5;
  const tracks::Track a = with_synthetic_fixes(track, o), b = with_synthetic_fixes(a, o);
  o.seed = 6;
  const tracks::Track c = with_synthetic_fixes(track, o);
  int same = 0, differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a.at(tracks::Col::aps_x, i)) continue;
    same += a.col(tracks::Col::aps_x)[i] == b.col(tracks::Col::aps_x)[i];
    differ += a.col(tracks::Col::aps_x)[i] != c.col(tracks::Col::aps_x)[i];
  }
  EXPECT_EQ(same, 30);
  EXPECT_EQ(differ, 30);
}

TEST(SyntheticFixes, RejectsBadOptionsAndTracksWithoutGroundTruth) {
  SyntheticFixOptions o;
  o.rate_hz = 0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("rate_hz"), std::string::npos);
  tracks::TrackData d;
  d.meta.name = "nogt";
  d.t = {0, 1};
  d.col(tracks::Col::v_cmd) = {0, 0};
  d.col(tracks::Col::w_cmd) = {0, 0};
  EXPECT_THROW(with_synthetic_fixes(tracks::Track(std::move(d)), SyntheticFixOptions{}), std::invalid_argument);
}

}  // namespace
}  // namespace odotune::sim

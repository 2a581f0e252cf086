// The innovation statistics of odotune/objectives/rl_innovations.h on sequences whose
// answer is known (consistent and white, covariance mis-scaled, correlated),
// and the replay's recording of innovations on a synthetic GPS drive
// (tests/support/rl_gps_bag.h).
#include <cmath>
#include <fstream>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/objectives/rl_innovations.h>
#include <odotune/objectives/rl_protocols.h>
#include <odotune/rlnode/gps_alignment.h>
#include <odotune/rlnode/params.h>

#include "support/rl_gps_bag.h"
#include "support/temp_dir.h"

namespace {

using namespace odotune;
using rlnode::Innovation;

// n innovations ν_k = L_k·z_k, z_k ~ N(0, I) (AR(1) with coefficient `rho`
// across k, unit variance), S_k = L_k·L_kᵀ·stated_over_true; S_k varies with k.
std::vector<Innovation> sequence(int n, double rho, double stated_over_true, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::vector<Innovation> v;
  Eigen::Vector2d z(g(rng), g(rng));
  for (int k = 0; k < n; ++k) {
    Eigen::Matrix2d L;
    L << 0.5 + 0.3 * std::sin(0.1 * k), 0.0, 0.1, 1.0 + 0.5 * std::cos(0.07 * k);
    const Eigen::Vector2d e(g(rng), g(rng));
    z = rho * z + std::sqrt(1.0 - rho * rho) * e;
    Innovation i;
    i.stamp_ns = k;
    i.nu = L * z;
    i.S = L * L.transpose() * stated_over_true;
    v.push_back(i);
  }
  return v;
}

double mean_logdet(const std::vector<Innovation>& v) {
  double s = 0.0;
  for (const Innovation& i : v) s += std::log(i.S.determinant());
  return s / static_cast<double>(v.size());
}

}  // namespace

TEST(RlInnovations, ConsistentWhiteInnovationsScoreNearTheirIdeal) {
  const std::vector<Innovation> v = sequence(20000, 0.0, 1.0, 7);
  EXPECT_LT(objectives::nis_cost(v), 0.03);         // mean NIS ≈ 2 (two dimensions)
  EXPECT_LT(objectives::whiteness_cost(v), 0.005);  // 10 lags of ≈ 1/√20000 each, squared
  EXPECT_NEAR(objectives::innovation_nll(v), 2.0 + mean_logdet(v), 0.05);
}

TEST(RlInnovations, AMisScaledCovarianceShowsInNisAndLikelihood) {
  const std::vector<Innovation> right = sequence(20000, 0.0, 1.0, 3);
  const std::vector<Innovation> over = sequence(20000, 0.0, 4.0, 3);
  const std::vector<Innovation> under = sequence(20000, 0.0, 0.25, 3);
  EXPECT_NEAR(objectives::nis_cost(over), std::log(4.0), 0.03);
  EXPECT_NEAR(objectives::nis_cost(under), std::log(4.0), 0.03);
  // The likelihood is least at the true scale: 2/k + 2 ln k is least at k = 1.
  EXPECT_LT(objectives::innovation_nll(right), objectives::innovation_nll(over));
  EXPECT_LT(objectives::innovation_nll(right), objectives::innovation_nll(under));
  EXPECT_GT(objectives::whiteness_cost(over), 0.5);  // its lag-0 term is ln(4)² ≈ 1.9
}

TEST(RlInnovations, CorrelatedInnovationsAreNotWhite) {
  const std::vector<Innovation> white = sequence(5000, 0.0, 1.0, 11);
  const std::vector<Innovation> red = sequence(5000, 0.8, 1.0, 11);
  EXPECT_LT(objectives::nis_cost(red), 0.1);  // consistent at lag 0 …
  // … but ρ_j ≈ 0.8^j: Σ_{j=1..10} 0.64^j ≈ 1.7.
  EXPECT_GT(objectives::whiteness_cost(red), 1.0);
  EXPECT_LT(objectives::whiteness_cost(white), 0.02);
  EXPECT_LT(objectives::whiteness_cost(red, 1), objectives::whiteness_cost(red, 10));
}

TEST(RlInnovations, UndefinedCasesAreNaN) {
  EXPECT_TRUE(std::isnan(objectives::innovation_nll({})));
  EXPECT_TRUE(std::isnan(objectives::nis_cost({})));
  EXPECT_TRUE(std::isnan(objectives::whiteness_cost(sequence(5, 0.0, 1.0, 1))));  // fewer than lags + 2
  std::vector<Innovation> v = sequence(100, 0.0, 1.0, 1);
  v[40].S(1, 1) = -1.0;
  EXPECT_TRUE(std::isnan(objectives::innovation_nll(v)));
  EXPECT_TRUE(std::isnan(objectives::nis_cost(v)));
  EXPECT_TRUE(std::isnan(objectives::whiteness_cost(v)));
  EXPECT_TRUE(std::isnan(objectives::heldout_nll({})));
}

TEST(RlInnovations, HeldOutLikelihoodAddsThePredictedAndTheFixCovariance) {
  rlnode::ReplayOutput o;
  rlnode::ScoredFix f;
  f.predicted = Eigen::Vector3d(1.0, 2.0, 0.0);
  f.measured = Eigen::Vector3d(2.0, 2.0, 5.0);  // z is not scored
  f.predicted_cov = Eigen::Matrix2d::Identity();
  f.fix_cov = Eigen::Matrix2d::Identity();
  o.scored.push_back(f);
  // C = 2·I, e = (1, 0): eᵀC⁻¹e = 0.5, ln det C = 2 ln 2.
  const std::vector<rlnode::ReplayOutput> one = {o};
  EXPECT_NEAR(objectives::heldout_nll(one), 0.5 + 2.0 * std::log(2.0), 1e-12);
  o.scored.push_back(f);
  o.scored.back().measured.x() = 1.0;  // e = 0: ln det C only
  const std::vector<rlnode::ReplayOutput> two = {o};
  EXPECT_NEAR(objectives::heldout_nll(two), 0.25 + 2.0 * std::log(2.0), 1e-12);
}

TEST(RlInnovations, TheReplayRecordsOneInnovationPerFusedFixOnlyWhenAsked) {
  testing_support::TempDir dir{"rl-innovations"};
  const auto params = dir.path() / "p.yaml";
  std::ofstream(params) << testing_support::kRlGpsParams;
  rlnode::Recording rec = rlnode::load_recording(testing_support::rl_gps_bag(dir.path(), 0.4),
                                                 rlnode::read_rl_params(params));
  rec.gps_transform = rlnode::fit_gps_alignment(rec, rlnode::settings_of(rec.params), 30.0).transform;
  const std::int64_t t0 = rec.fixes.front().stamp_ns;
  const std::vector<rlnode::FixRole> roles = objectives::every_fifth_roles(rec, t0,
                                                                           rec.fixes.back().stamp_ns + 1);
  const rlnode::Schedule schedule = rlnode::make_schedule(rec, roles);
  rlnode::ReplaySettings settings = rlnode::settings_of(rec.params);
  EXPECT_TRUE(rlnode::replay(rec, schedule, settings).innovations.empty());
  settings.innovations = true;
  const rlnode::ReplayOutput out = rlnode::replay(rec, schedule, settings);
  long fused = 0;
  for (const rlnode::FixRole r : roles) fused += r == rlnode::FixRole::fuse;
  ASSERT_EQ(static_cast<long>(out.innovations.size()), fused);
  for (std::size_t k = 0; k < out.innovations.size(); ++k) {
    const Innovation& i = out.innovations[k];
    EXPECT_GT(i.S.determinant(), 0.0) << k;
    EXPECT_TRUE(i.nu.allFinite()) << k;
    if (k > 0) {
      EXPECT_GT(i.stamp_ns, out.innovations[k - 1].stamp_ns);
    }
  }
  ASSERT_FALSE(out.scored.empty());
  for (const rlnode::ScoredFix& f : out.scored) EXPECT_GT(f.predicted_cov.determinant(), 0.0);
  EXPECT_TRUE(std::isfinite(objectives::innovation_nll(out.innovations)));
  EXPECT_TRUE(std::isfinite(objectives::heldout_nll(std::vector<rlnode::ReplayOutput>{out})));
}

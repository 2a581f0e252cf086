// Fading memory (odotune/filters/pf_evolution.h) and the slow/fast memory pair that
// finds changes (odotune/filters/memory_pair.h), on the DKF with synthetic samples:
// a static robot gets no false change in 20 minutes and a sharper estimate
// than the fast twin's; a 1 % radius step is found within seconds and
// tracked; the memory's inflation and growth follow the header.
#include <cmath>
#include <random>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/filters/dual_kf.h>
#include <odotune/filters/memory_pair.h>
#include <odotune/filters/pf_evolution.h>

namespace odotune::filters {
namespace {

using ::testing::HasSubstr;

constexpr double kDt = 0.1;  // 10 Hz measurements [s]

// Samples of a robot with radii `truth(t)` and wheel base 0.65 m driving
// varied wheel rates, measured with white noise σ 0.02 (m/s, rad/s).
template <class Truth>
std::vector<CalibSample> drive(double seconds, Truth truth, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 0.02);
  std::vector<CalibSample> out;
  for (double t = kDt; t <= seconds + 1e-9; t += kDt) {
    CalibSample s;
    s.dt_s = kDt;
    s.omega_l_rad_s = 3.0 + 1.5 * std::sin(0.3 * t);
    s.omega_r_rad_s = 3.0 + 1.5 * std::cos(0.2 * t);
    const BodyVelocity v = body_velocity(truth(t), s.omega_l_rad_s, s.omega_r_rad_s);
    s.v_m_s = v.v_m_s + n(rng);
    s.w_rad_s = v.w_rad_s + n(rng);
    out.push_back(s);
  }
  return out;
}

OdometryParams params(double r) { return {r, r, 0.65}; }

TEST(EvidenceMemory, InflationIsExpOfDtOverMemoryAndTheMemoryGrows) {
  EvidenceMemoryParams p;
  EvidenceMemory m(p);
  EXPECT_NEAR(m.step(kDt), std::expm1(kDt / p.min_memory_s), 1e-15);
  EXPECT_NEAR(m.memory_s(), p.min_memory_s + kDt, 1e-12);
  for (int i = 0; i < 100000; ++i) m.step(kDt);
  EXPECT_DOUBLE_EQ(m.memory_s(), p.max_memory_s);
  EXPECT_DOUBLE_EQ(m.step(0.0), 0.0);
  m.restart();
  EXPECT_DOUBLE_EQ(m.memory_s(), p.min_memory_s);
  std::string why;
  p.max_memory_s = 1.0;  // < min
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("max_memory_s"));
  MemoryPairParams pair;
  pair.cusum_threshold = 0.0;
  EXPECT_FALSE(pair.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("cusum_threshold"));
}

TEST(MemoryPair, AStaticRobotKeepsItsMemoryAndASharperEstimate) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    DualKfParams p;  // starts at 0.32 m, truth 0.3232 m (+1 %)
    MemoryPair<DualKf> pair(DualKf(p), p.evidence, MemoryPairParams{});
    double ss_slow = 0.0, ss_fast = 0.0;
    const std::vector<CalibSample> samples = drive(
        1200.0, [](double) { return params(0.3232); }, seed);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      pair.step(samples[i]);
      if (i * 2 < samples.size()) continue;  // the second half
      ss_slow += std::pow(pair.estimate().params.wheel_radius_left_m - 0.3232, 2);
      ss_fast += std::pow(pair.fast().estimate().params.wheel_radius_left_m - 0.3232, 2);
    }
    EXPECT_EQ(pair.changes(), 0) << "seed " << seed;
    EXPECT_DOUBLE_EQ(pair.slow().memory_s(), p.evidence.max_memory_s);
    EXPECT_LT(ss_slow, 0.25 * ss_fast) << "seed " << seed;  // a long memory pays
    EXPECT_NEAR(pair.estimate().params.wheel_radius_left_m, 0.3232, 0.001 * 0.3232);
  }
}

TEST(MemoryPair, ARadiusStepIsFoundAndTracked) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    DualKfParams p;
    MemoryPair<DualKf> pair(DualKf(p), p.evidence, MemoryPairParams{});
    const auto truth = [](double t) { return params(t < 300.0 ? 0.3232 : 0.3232 * 0.99); };
    const std::vector<CalibSample> samples = drive(400.0, truth, seed);
    double found_after_s = -1.0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const long before = pair.changes();
      pair.step(samples[i]);
      const double t = kDt * static_cast<double>(i + 1);
      if (pair.changes() > before && t >= 300.0 && found_after_s < 0.0) found_after_s = t - 300.0;
    }
    EXPECT_EQ(pair.changes(), 1) << "seed " << seed;
    ASSERT_GE(found_after_s, 0.0) << "seed " << seed;
    EXPECT_LT(found_after_s, 30.0) << "seed " << seed;
    EXPECT_NEAR(pair.estimate().params.wheel_radius_left_m, 0.3232 * 0.99, 0.002 * 0.3232) << "seed " << seed;
  }
}

}  // namespace
}  // namespace odotune::filters

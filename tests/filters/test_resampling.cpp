// Resampling (odotune/filters/resampling.h): every scheme unbiased, the low-variance
// schemes below multinomial's copy-count variance, output contract (sorted,
// any output size, zero weights never drawn, reproducible), N_eff, parsing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <odotune/filters/odometry_params.h>
#include <odotune/filters/resampling.h>

namespace odotune::filters {
namespace {

constexpr Resampler kAllSchemes[] = {Resampler::multinomial, Resampler::stratified, Resampler::systematic,
                                     Resampler::residual};

// A lopsided weight vector with zeros, weights above and below 1/N, and one
// particle holding several expected copies.
std::vector<double> test_weights() {
  std::vector<double> w = {0.0, 1.0, 2.0, 0.5, 9.0, 0.0, 3.0, 0.25, 6.5, 1.75,
                           0.0, 4.0, 0.1, 2.9, 0.0, 5.0, 1.2, 0.8,  3.3, 0.0};
  double sum = 0.0;
  for (const double x : w) sum += x;
  for (double& x : w) x /= sum;
  return w;
}

// Copy counts of each particle in one resampling.
std::vector<int> copies(Resampler scheme, const std::vector<double>& w, std::uint64_t seed,
                        std::uint64_t iteration, int draws) {
  std::vector<int> out(static_cast<std::size_t>(draws), -1);
  resample(scheme, w, seed, iteration, out);
  std::vector<int> c(w.size(), 0);
  for (const int a : out) {
    EXPECT_GE(a, 0);
    EXPECT_LT(a, static_cast<int>(w.size()));
    if (a >= 0 && a < static_cast<int>(w.size())) ++c[static_cast<std::size_t>(a)];
  }
  EXPECT_TRUE(std::is_sorted(out.begin(), out.end())) << to_string(scheme);
  return c;
}

struct CopyStats {
  std::vector<double> mean, var;  // per particle, over the trials
};

CopyStats copy_stats(Resampler scheme, const std::vector<double>& w, int draws, int trials) {
  const std::size_t n = w.size();
  std::vector<double> s1(n, 0.0), s2(n, 0.0);
  for (int t = 0; t < trials; ++t) {
    const std::vector<int> c = copies(scheme, w, 42, static_cast<std::uint64_t>(t) + 1, draws);
    int total = 0;
    for (std::size_t i = 0; i < n; ++i) {
      s1[i] += c[i];
      s2[i] += static_cast<double>(c[i]) * c[i];
      total += c[i];
    }
    EXPECT_EQ(total, draws);
  }
  CopyStats st{std::vector<double>(n), std::vector<double>(n)};
  const double tr = trials;
  for (std::size_t i = 0; i < n; ++i) {
    st.mean[i] = s1[i] / tr;
    st.var[i] = (s2[i] - s1[i] * s1[i] / tr) / (tr - 1.0);
  }
  return st;
}

// E[copies of i] = M ρ_i. The tolerance is 5 standard errors of the mean,
// from each scheme's own per-particle sample variance (a scheme whose count
// for i never varies must hit M ρ_i exactly, so M ρ_i must be an integer).
TEST(Resampling, EverySchemeIsUnbiasedForSeveralOutputSizes) {
  const std::vector<double> w = test_weights();
  constexpr int kTrials = 2000;
  for (const Resampler scheme : kAllSchemes) {
    for (const int draws : {20, 33, 7}) {  // = N, > N, < N
      const CopyStats st = copy_stats(scheme, w, draws, kTrials);
      for (std::size_t i = 0; i < w.size(); ++i) {
        const double expected = draws * w[i];
        const double se = std::sqrt(st.var[i] / kTrials);
        EXPECT_NEAR(st.mean[i], expected, 5.0 * se + 1e-12)
            << to_string(scheme) << " M=" << draws << " particle " << i;
        if (w[i] == 0.0) {
          EXPECT_EQ(st.mean[i], 0.0) << to_string(scheme) << " drew a zero weight";
        }
      }
    }
  }
}

// Multinomial copies of i are Binomial(M, ρ_i): the sample variance matches
// M ρ(1−ρ) within 5 standard errors of a sample variance,
// σ²·√(2/(T−1) + κ/T) with κ the binomial's excess kurtosis.
TEST(Resampling, MultinomialCopiesHaveBinomialVariance) {
  const std::vector<double> w = test_weights();
  constexpr int kTrials = 2000;
  constexpr int kDraws = 20;
  const CopyStats st = copy_stats(Resampler::multinomial, w, kDraws, kTrials);
  for (std::size_t i = 0; i < w.size(); ++i) {
    if (w[i] == 0.0) continue;
    const double p = w[i];
    const double var = kDraws * p * (1.0 - p);
    const double kurt = (1.0 - 6.0 * p * (1.0 - p)) / var;
    const double se = var * std::sqrt(2.0 / (kTrials - 1) + kurt / kTrials);
    EXPECT_NEAR(st.var[i], var, 5.0 * se) << "particle " << i;
  }
}

// The low-variance schemes (Li, Bolić & Djurić 2015): per-particle copy-count
// variance, averaged over the particles, below multinomial's (here
// multinomial's average is (M/N)(1 − Σρ²) ≈ 0.88; systematic's is below 1/4,
// residual's is the multinomial variance of the residuals only).
TEST(Resampling, LowVarianceSchemesBeatMultinomial) {
  const std::vector<double> w = test_weights();
  constexpr int kTrials = 2000;
  constexpr int kDraws = 20;
  auto mean_var = [&](Resampler scheme) {
    const CopyStats st = copy_stats(scheme, w, kDraws, kTrials);
    double sum = 0.0;
    for (const double v : st.var) sum += v;
    return sum / static_cast<double>(w.size());
  };
  const double multinomial = mean_var(Resampler::multinomial);
  for (const Resampler scheme : {Resampler::stratified, Resampler::systematic, Resampler::residual}) {
    const double v = mean_var(scheme);
    EXPECT_LT(v, multinomial) << to_string(scheme) << ": " << v << " vs " << multinomial;
  }
  // Systematic: each count is ⌊Mρ_i⌋ or ⌈Mρ_i⌉, so its variance ≤ 1/4.
  const CopyStats sys = copy_stats(Resampler::systematic, w, kDraws, kTrials);
  for (std::size_t i = 0; i < w.size(); ++i) {
    EXPECT_LE(sys.var[i], 0.25 + 0.05) << "particle " << i;
    const double mr = kDraws * w[i];
    EXPECT_GE(sys.mean[i], std::floor(mr));
    EXPECT_LE(sys.mean[i], std::ceil(mr));
  }
}

// Every single systematic draw (not only the mean) gives each particle
// ⌊Mρ_i⌋ or ⌈Mρ_i⌉ copies, here on thousands of particles with runs of zero
// weights and particles worth several copies, M both below and above N: the
// counts, their expansion into sorted ancestors and the vectorised loops agree
// with the scheme's definition (eq. 8).
TEST(Resampling, SystematicCountsAreFloorOrCeilOnLargeClouds) {
  constexpr std::size_t kN = 5003;  // not a multiple of any vector width
  std::vector<double> w(kN);
  std::uint64_t state = 12345;
  double sum = 0.0;
  for (std::size_t i = 0; i < kN; ++i) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const double u = static_cast<double>(state >> 11) * 0x1.0p-53;
    w[i] = (i / 50) % 3 == 0 ? 0.0 : (u < 0.01 ? 40.0 * u / 0.01 : u);
    sum += w[i];
  }
  for (double& x : w) x /= sum;
  for (const int draws : {1, 977, 5003, 12000}) {
    for (std::uint64_t it = 1; it <= 5; ++it) {
      const std::vector<int> c = copies(Resampler::systematic, w, 3, it, draws);
      for (std::size_t i = 0; i < kN; ++i) {
        const double mr = draws * w[i];
        const int lo = std::max(0, static_cast<int>(std::floor(mr - 1e-9)));  // rounding of C_i·M/T
        const int hi = static_cast<int>(std::ceil(mr + 1e-9));
        ASSERT_GE(c[i], lo) << "particle " << i << ", M = " << draws;
        ASSERT_LE(c[i], hi) << "particle " << i << ", M = " << draws;
        if (w[i] == 0.0) {
          ASSERT_EQ(c[i], 0) << "particle " << i;
        }
      }
    }
  }
}

TEST(Resampling, DeterministicGivenSeedAndIteration) {
  const std::vector<double> w = test_weights();
  for (const Resampler scheme : kAllSchemes) {
    std::vector<int> a(50), b(50), c(50), d(50);
    resample(scheme, w, 7, 3, a);
    resample(scheme, w, 7, 3, b);
    EXPECT_EQ(a, b) << to_string(scheme);
    // Another iteration or seed gives another draw (with 50 draws over 20
    // particles an identical outcome is very unlikely for every scheme).
    bool differs_iteration = false, differs_seed = false;
    for (std::uint64_t k = 4; k < 14; ++k) {
      resample(scheme, w, 7, k, c);
      resample(scheme, w, 7 + k, 3, d);
      differs_iteration |= c != a;
      differs_seed |= d != a;
    }
    EXPECT_TRUE(differs_iteration) << to_string(scheme);
    EXPECT_TRUE(differs_seed) << to_string(scheme);
  }
}

TEST(Resampling, OneHotAndUnnormalisedWeights) {
  std::vector<double> w(10, 0.0);
  w[6] = 1.0;
  for (const Resampler scheme : kAllSchemes) {
    std::vector<int> out(13);
    resample(scheme, w, 1, 1, out);
    for (const int a : out) EXPECT_EQ(a, 6) << to_string(scheme);
  }
  // Weights ∝ ρ are accepted: scaling them leaves the draw unchanged.
  const std::vector<double> rho = test_weights();
  std::vector<double> scaled = rho;
  for (double& x : scaled) x *= 4.0;  // exact scaling by a power of two
  for (const Resampler scheme : kAllSchemes) {
    std::vector<int> a(25), b(25);
    resample(scheme, rho, 9, 2, a);
    resample(scheme, scaled, 9, 2, b);
    EXPECT_EQ(a, b) << to_string(scheme);
  }
}

TEST(Resampling, RejectsUnusableWeights) {
  std::vector<int> out(5);
  EXPECT_THROW(resample(Resampler::systematic, std::vector<double>{}, 1, 1, out), std::invalid_argument);
  EXPECT_THROW(resample(Resampler::systematic, std::vector<double>{0.0, 0.0}, 1, 1, out),
               std::invalid_argument);
  EXPECT_THROW(resample(Resampler::multinomial, std::vector<double>{1.0, NAN}, 1, 1, out),
               std::invalid_argument);
  std::vector<int> none;
  EXPECT_NO_THROW(resample(Resampler::residual, std::vector<double>{1.0}, 1, 1, none));
}

TEST(Resampling, EffectiveSampleSize) {
  const std::vector<double> uniform(250, 1.0 / 250.0);
  EXPECT_NEAR(effective_sample_size(uniform), 250.0, 1e-9);
  std::vector<double> one_hot(40, 0.0);
  one_hot[17] = 1.0;
  EXPECT_DOUBLE_EQ(effective_sample_size(one_hot), 1.0);
  // Two equal halves: N_eff = 2.
  std::vector<double> two(8, 0.0);
  two[1] = two[5] = 0.5;
  EXPECT_DOUBLE_EQ(effective_sample_size(two), 2.0);
}

TEST(Resampling, ParseAndToStringRoundTrip) {
  for (const Resampler r : kAllSchemes) {
    Resampler parsed = r == Resampler::multinomial ? Resampler::residual : Resampler::multinomial;
    ASSERT_TRUE(parse_resampler(to_string(r), &parsed)) << to_string(r);
    EXPECT_EQ(parsed, r);
  }
  for (const ResamplePolicy p :
       {ResamplePolicy::every_step, ResamplePolicy::neff, ResamplePolicy::max_weight}) {
    ResamplePolicy parsed = p == ResamplePolicy::neff ? ResamplePolicy::every_step : ResamplePolicy::neff;
    ASSERT_TRUE(parse_resample_policy(to_string(p), &parsed)) << to_string(p);
    EXPECT_EQ(parsed, p);
  }
  EXPECT_EQ(to_string(ResamplePolicy::every_step), "every");
  EXPECT_EQ(to_string(ResamplePolicy::max_weight), "max");
  Resampler r = Resampler::stratified;
  EXPECT_FALSE(parse_resampler("Systematic", &r));
  EXPECT_FALSE(parse_resampler("", &r));
  EXPECT_EQ(r, Resampler::stratified);
  ResamplePolicy p = ResamplePolicy::max_weight;
  EXPECT_FALSE(parse_resample_policy("every_step", &p));
  EXPECT_EQ(p, ResamplePolicy::max_weight);
}

TEST(OdometryParams, IsValidNamesTheBadField) {
  std::string why;
  EXPECT_TRUE((OdometryParams{0.3, 0.31, 0.6}.IsValid(&why)));
  EXPECT_FALSE((OdometryParams{0.3, 0.31, -1.0}.IsValid(&why)));
  EXPECT_NE(why.find("wheel_base_m = -1"), std::string::npos) << why;
  EXPECT_FALSE((OdometryParams{NAN, 0.31, 0.6}.IsValid(&why)));
  EXPECT_NE(why.find("wheel_radius_left_m"), std::string::npos) << why;
  EXPECT_FALSE((OdometryParams{0.3, 0.0, 0.6}.IsValid(&why)));
  EXPECT_NE(why.find("wheel_radius_right_m = 0"), std::string::npos) << why;
  EXPECT_FALSE((OdometryParams{0.3, 0.0, 0.6}.IsValid(nullptr)));
}

TEST(OdometryParams, BodyVelocityKinematics) {
  const OdometryParams p{0.30, 0.32, 0.60};
  // Straight: both wheels cover 1 m/s.
  const BodyVelocity straight = body_velocity(p, 1.0 / 0.30, 1.0 / 0.32);
  EXPECT_NEAR(straight.v_m_s, 1.0, 1e-12);
  EXPECT_NEAR(straight.w_rad_s, 0.0, 1e-12);
  // Spin on the spot: right wheel +0.3 m/s, left −0.3 m/s → W = 0.6/D.
  const BodyVelocity spin = body_velocity(p, -0.3 / 0.30, 0.3 / 0.32);
  EXPECT_NEAR(spin.v_m_s, 0.0, 1e-12);
  EXPECT_NEAR(spin.w_rad_s, 1.0, 1e-12);
}

}  // namespace
}  // namespace odotune::filters

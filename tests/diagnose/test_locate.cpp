// Locating residual growth (odotune/diagnose/locate.h) on synthetic residual
// series: a robot on a figure-eight with a time-varying pace, dead-reckoning
// residuals re-anchored every 20 s, built from an injected growth (known
// segment, region or condition) plus reference noise and an odometry random
// walk. Everything is generated here with seeded noise.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include <odotune/diagnose/locate.h>
#include <odotune/sim/normal_rng.h>

namespace odotune::diagnose {
namespace {

struct State {
  double t, x, y, theta, v, w, a;
};

// Figure-eight x = 3 sin φ, y = 1.5 sin 2φ (period 40 s of φ/ω), with the
// pace modulated so that speed and turn rate are not functions of place.
void pose_at(double t, double* x, double* y) {
  const double om = 2 * std::numbers::pi / 40.0;
  const double phi = om * (t + 0.4 * 23.0 / (2 * std::numbers::pi) *
                                   (1 - std::cos(2 * std::numbers::pi * t / 23.0)));
  *x = 3.0 * std::sin(phi);
  *y = 1.5 * std::sin(2 * phi);
}

State state_at(double t) {
  const double h = 1e-3;
  double xa, ya, xb, yb, xc, yc;
  pose_at(t - h, &xa, &ya);
  pose_at(t, &xb, &yb);
  pose_at(t + h, &xc, &yc);
  const double th0 = std::atan2(yb - ya, xb - xa), th1 = std::atan2(yc - yb, xc - xb);
  const double v = std::hypot(xc - xa, yc - ya) / (2 * h);
  const double v0 = std::hypot(xb - xa, yb - ya) / h, v1 = std::hypot(xc - xb, yc - yb) / h;
  return {t,
          xb,
          yb,
          std::atan2(yc - ya, xc - xa),
          v,
          std::remainder(th1 - th0, 2 * std::numbers::pi) / h,
          (v1 - v0) / h};
}

// Growth [m/s, world frame] injected at a state.
using Injection = std::function<void(const State&, double* gx, double* gy)>;

struct SeriesSpec {
  double duration_s = 200.0, rate_hz = 50.0, window_s = 20.0;
  double ref_sigma_m = 0.005;  // white noise of the reference, per axis
  double walk_sigma_m = 2e-4;  // odometry random walk per row, per axis
  bool heading = false;
  std::uint64_t seed = 1;
};

ResidualSeries make_series(const SeriesSpec& sp, const Injection& inject) {
  sim::Normal ref(sim::splitmix64(sp.seed)), walk(sim::splitmix64(sp.seed + 7));
  ResidualSeries s;
  const double dt = 1.0 / sp.rate_hz;
  const int n = static_cast<int>(std::round(sp.duration_s * sp.rate_hz));
  double ex = 0, ey = 0, eth = 0;
  int window = -1;
  for (int k = 0; k <= n; ++k) {
    const double t = k * dt;
    const int wid = static_cast<int>(std::floor(t / sp.window_s + 1e-9));
    const State st = state_at(t);
    if (wid != window) {
      window = wid, ex = ey = eth = 0;
    } else {
      double gx = 0, gy = 0;
      inject(st, &gx, &gy);
      ex += gx * dt + sp.walk_sigma_m * walk();
      ey += gy * dt + sp.walk_sigma_m * walk();
      eth += 1e-5 * walk();
    }
    s.t_s.push_back(t);
    s.window.push_back(wid);
    s.ex_m.push_back(ex + sp.ref_sigma_m * ref());
    s.ey_m.push_back(ey + sp.ref_sigma_m * ref());
    if (sp.heading) s.e_theta_rad.push_back(eth + 1e-4 * ref());
    s.x_m.push_back(st.x), s.y_m.push_back(st.y), s.v_mps.push_back(st.v), s.w_radps.push_back(st.w);
    s.accel_mps2.push_back(st.a), s.t_since_start_s.push_back(t);
  }
  return s;
}

const Injection kNothing = [](const State&, double*, double*) {};

TEST(Locate, OptionsAndSeriesValidation) {
  std::string why;
  EXPECT_TRUE(LocateOptions{}.IsValid(&why)) << why;
  LocateOptions o;
  o.threshold_sigma = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("threshold_sigma"), std::string::npos);

  ResidualSeries s = make_series({.duration_s = 30}, kNothing);
  EXPECT_TRUE(s.IsValid(&why)) << why;
  s.v_mps.pop_back();
  EXPECT_FALSE(s.IsValid(&why));
  EXPECT_NE(why.find("v_mps"), std::string::npos) << why;
  EXPECT_THROW(locate(s, 0.0), std::invalid_argument);
  s = make_series({.duration_s = 30}, kNothing);
  s.t_s[5] = s.t_s[4];
  EXPECT_FALSE(s.IsValid(&why));
  EXPECT_NE(why.find("t_s[5]"), std::string::npos) << why;
  s = make_series({.duration_s = 30}, kNothing);
  EXPECT_THROW(locate(s, -1.0), std::invalid_argument);
  EXPECT_THROW(locate(s, 0.01, o), std::invalid_argument);
}

TEST(Locate, PureNoiseFindsNothing) {
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    for (const bool fixes : {false, true}) {
      SeriesSpec sp{.seed = seed};
      if (fixes) sp.rate_hz = 1.0, sp.ref_sigma_m = 0.06, sp.walk_sigma_m = 0.002;
      const Location loc = locate(make_series(sp, kNothing), sp.ref_sigma_m);
      EXPECT_TRUE(loc.segments.empty())
          << "seed " << seed << " fixes " << fixes << " t0 " << loc.segments.front().t0_s;
      EXPECT_TRUE(loc.regions.empty()) << "seed " << seed << " fixes " << fixes;
      EXPECT_EQ(loc.phrase, "") << "seed " << seed << " fixes " << fixes;
      EXPECT_EQ(loc.flagged_count, 0) << "seed " << seed;
      // 4σ on a 2-D Gaussian: P = e^-8 = 3.4e-4 per row, ~3 of 10000 rows.
      EXPECT_LE(loc.exceedances, 12) << "seed " << seed;
      EXPECT_EQ(loc.conditions.size(), 7u);
    }
  }
}

TEST(Locate, NoiseLevelEstimateMatchesTheWhiteNoise) {
  const SeriesSpec sp{.walk_sigma_m = 0.0, .seed = 3};
  const Location loc = locate(make_series(sp, kNothing), 0.0);
  // Difference of two positions over a 1 s span: √2·σ/span per axis.
  EXPECT_NEAR(loc.sigma_growth_mps, std::sqrt(2.0) * sp.ref_sigma_m / loc.span_s, 0.1 * 0.00707);
  EXPECT_DOUBLE_EQ(loc.span_s, 1.0);
}

TEST(Locate, FindsAnInjectedTimeSegment) {
  const Injection burst = [](const State& st, double* gx, double* gy) {
    if (st.t >= 73.0 && st.t <= 81.0) *gx = 0.05 * std::cos(st.theta), *gy = 0.05 * std::sin(st.theta);
  };
  const Location loc = locate(make_series({.seed = 5}, burst), 0.005);
  ASSERT_EQ(loc.segments.size(), 1u);
  EXPECT_NEAR(loc.segments[0].t0_s, 73.0, 1.0);
  EXPECT_NEAR(loc.segments[0].t1_s, 81.0, 1.0);
  EXPECT_GT(loc.segments[0].peak_z, 4.0);
  // Time is the condition it depends on (only rows in [73, 81]), but it is
  // not monotone in time; the phrase must not invent a place.
  EXPECT_TRUE(loc.regions.empty() || loc.regions[0].x1_m - loc.regions[0].x0_m < 3.0);
}

TEST(Locate, FindsAnInjectedRegionOfTheFloor) {
  // Slip-zone-like: the odometry over-reads 10 % of the travel inside a box.
  const double bx0 = 1.0, bx1 = 2.0, by0 = 0.4, by1 = 1.4;
  const Injection zone = [&](const State& st, double* gx, double* gy) {
    if (st.x >= bx0 && st.x <= bx1 && st.y >= by0 && st.y <= by1) {
      *gx = 0.1 * st.v * std::cos(st.theta), *gy = 0.1 * st.v * std::sin(st.theta);
    }
  };
  const Location loc = locate(make_series({.seed = 6}, zone), 0.005);
  ASSERT_FALSE(loc.regions.empty());
  const MapRegion& r = loc.regions[0];
  // The box found holds the true box's centre and is at most a cell or two
  // (the growth span smears by v·span/2) larger than the truth on each side.
  EXPECT_LE(r.x0_m, 0.5 * (bx0 + bx1));
  EXPECT_GE(r.x1_m, 0.5 * (bx0 + bx1));
  EXPECT_LE(r.y0_m, 0.5 * (by0 + by1));
  EXPECT_GE(r.y1_m, 0.5 * (by0 + by1));
  EXPECT_GT(r.x0_m, bx0 - 1.0);
  EXPECT_LT(r.x1_m, bx1 + 1.0);
  EXPECT_GT(r.y0_m, by0 - 1.0);
  EXPECT_LT(r.y1_m, by1 + 1.0);
  // One pass per 40 s lap through the zone: 5 segments.
  EXPECT_EQ(loc.segments.size(), 5u);
}

TEST(Locate, LateralSkidLikeGrowthRanksTurnSpeedFirst) {
  // Sideways drift v_y = −k·v·w (world frame: perpendicular to the heading).
  const Injection skid = [](const State& st, double* gx, double* gy) {
    const double vy = -0.08 * st.v * st.w;
    *gx = -vy * std::sin(st.theta), *gy = vy * std::cos(st.theta);
  };
  const Location loc = locate(make_series({.seed = 8}, skid), 0.005);
  ASSERT_GT(loc.flagged_count, 0);
  ASSERT_EQ(loc.conditions.size(), 7u);
  EXPECT_EQ(loc.conditions[0].condition, Condition::turn_speed)
      << "strongest " << condition_name(loc.conditions[0].condition) << " rho " << loc.conditions[0].rho
      << " second " << condition_name(loc.conditions[1].condition) << " rho " << loc.conditions[1].rho;
  EXPECT_GT(loc.conditions[0].rho, 0.3);
  EXPECT_TRUE(loc.conditions[0].above);
  EXPECT_NE(loc.phrase.find("|v*w| above"), std::string::npos) << loc.phrase;
  for (std::size_t i = 1; i < loc.conditions.size(); ++i) {
    EXPECT_GE(std::abs(loc.conditions[i - 1].rho), std::abs(loc.conditions[i].rho));
  }
}

TEST(Locate, RadiusStepLikeGrowthRanksTimeFirst) {
  // From t = 120 s the odometry over-reads travel by 1.5 %: growth 0.015·v.
  const Injection step = [](const State& st, double* gx, double* gy) {
    if (st.t >= 120.0) *gx = 0.015 * st.v * std::cos(st.theta), *gy = 0.015 * st.v * std::sin(st.theta);
  };
  const SeriesSpec sp{.ref_sigma_m = 0.0005, .walk_sigma_m = 2e-5, .heading = true, .seed = 9};
  const Location loc = locate(make_series(sp, step), sp.ref_sigma_m);
  ASSERT_FALSE(loc.segments.empty());
  EXPECT_NEAR(loc.segments.front().t0_s, 120.0, 5.0);
  EXPECT_GT(loc.segments.back().t1_s, 190.0);
  EXPECT_EQ(loc.conditions[0].condition, Condition::time);
  EXPECT_NEAR(loc.conditions[0].threshold, 120.0, 12.0);
  EXPECT_EQ(loc.phrase.rfind("after t = ", 0), 0u) << loc.phrase;
  EXPECT_GT(loc.sigma_growth_radps, 0.0);
}

TEST(Locate, SpeedDependentGrowthGivesTwoPartPhrase) {
  // Growth only in fast turns: |w| > 0.4 rad/s and v > 0.45 m/s.
  const Injection fast_turns = [](const State& st, double* gx, double* gy) {
    if (std::abs(st.w) > 0.4 && st.v > 0.45) *gx = 0.04 * std::cos(st.theta), *gy = 0.04 * std::sin(st.theta);
  };
  const Location loc = locate(make_series({.seed = 10}, fast_turns), 0.005);
  ASSERT_GT(loc.flagged_count, 0);
  // Two parts: the speed (v > 0.45) and the turning (|w| > 0.4, or
  // equivalently |v·w| > ~0.45·0.4), each with a threshold near the truth.
  ASSERT_EQ(loc.phrase_parts.size(), 2u) << loc.phrase;
  bool speed = false, turn = false;
  for (const ConditionPart& p : loc.phrase_parts) {
    EXPECT_TRUE(p.above) << loc.phrase;
    if (p.condition == Condition::speed) {
      speed = true;
      EXPECT_NEAR(p.threshold, 0.45, 0.1) << loc.phrase;
    } else if (p.condition == Condition::turn_rate) {
      turn = true;
      EXPECT_NEAR(p.threshold, 0.4, 0.1) << loc.phrase;
    } else if (p.condition == Condition::turn_speed) {
      turn = true;
      EXPECT_NEAR(p.threshold, 0.18, 0.06) << loc.phrase;
    }
  }
  EXPECT_TRUE(speed && turn) << loc.phrase;
  EXPECT_NE(loc.phrase.find(" at speeds above 0."), std::string::npos) << loc.phrase;
}

}  // namespace
}  // namespace odotune::diagnose

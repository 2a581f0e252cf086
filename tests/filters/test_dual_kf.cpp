// Dual Kalman filter calibration (odotune/filters/dual_kf.h): the parameter filter's
// Jacobian against central differences, convergence on the synthetic stream
// (0.5 % of the true radii), covariance properties, parameter checks.
#include <gtest/gtest.h>

#include <Eigen/LU>  // determinant()
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <odotune/filters/dual_kf.h>

#include "support/calib_stream.h"

namespace odotune::filters {
namespace {

using testing::make_stream;
using testing::radius_error;
using testing::Stream;
using testing::StreamSpec;

DkfVelocity h_of(const DkfParams& theta, double wl, double wr) {
  const BodyVelocity b = body_velocity(
      OdometryParams{theta(kDkfRadiusLeft), theta(kDkfRadiusRight), theta(kDkfWheelBase)}, wl, wr);
  return DkfVelocity(b.v_m_s, b.w_rad_s);
}

TEST(DualKf, JacobianMatchesCentralDifferences) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> radius(0.2, 0.4), base(0.4, 0.9), rate(-6.0, 6.0);
  for (int trial = 0; trial < 200; ++trial) {
    const DkfParams theta(radius(rng), radius(rng), base(rng));
    const double wl = rate(rng), wr = rate(rng);
    const DkfJacobian j = dkf_jacobian(theta, wl, wr);
    const double step = 1e-6;
    for (int c = 0; c < kDkfParamDim; ++c) {
      DkfParams tp = theta, tm = theta;
      tp(c) += step;
      tm(c) -= step;
      const DkfVelocity num = (h_of(tp, wl, wr) - h_of(tm, wl, wr)) / (2.0 * step);
      for (int r = 0; r < kDkfVelocityDim; ++r)
        EXPECT_NEAR(j(r, c), num(r), 1e-7 * (1.0 + std::abs(num(r)))) << r << "," << c;
    }
  }
}

bool symmetric_positive_definite(const DkfParamCov& p) {
  if (!p.allFinite() || (p - p.transpose()).cwiseAbs().maxCoeff() > 1e-15 * p.cwiseAbs().maxCoeff())
    return false;
  return p(0, 0) > 0.0 && p.topLeftCorner<2, 2>().determinant() > 0.0 && p.determinant() > 0.0;
}

// From the wheelchair nominal (0.32, 0.32, 0.65) to R_R = 0.318, R_L = 0.326
// (0.6 % and 1.8 % off): within 0.5 % on average over the last 30 s of a
// 60 s drive, and at every sample of that window within 1 %.
TEST(DualKf, ConvergesToTheTrueRadii) {
  StreamSpec spec;
  spec.duration_s = 60.0;
  const Stream s = make_stream(spec);
  DualKf dkf(DualKfParams{});
  EXPECT_GT(radius_error(dkf.estimate().params, spec.truth), 0.01);
  OdometryParams mean{0.0, 0.0, 0.0};
  int n = 0;
  for (std::size_t k = 0; k < s.samples.size(); ++k) {
    const CalibEstimate& e = dkf.step(s.samples[k]);
    ASSERT_TRUE(symmetric_positive_definite(dkf.param_covariance())) << k;
    EXPECT_EQ(e.sd_radius_right_m, std::sqrt(dkf.param_covariance()(kDkfRadiusRight, kDkfRadiusRight)));
    EXPECT_EQ(e.particles, 0);
    if (s.t[k] < 30.0) continue;
    EXPECT_LT(radius_error(e.params, spec.truth), 0.01) << s.t[k];
    mean.wheel_radius_left_m += e.params.wheel_radius_left_m;
    mean.wheel_radius_right_m += e.params.wheel_radius_right_m;
    mean.wheel_base_m += e.params.wheel_base_m;
    ++n;
  }
  mean.wheel_radius_left_m /= n;
  mean.wheel_radius_right_m /= n;
  mean.wheel_base_m /= n;
  EXPECT_LT(radius_error(mean, spec.truth), 0.005);
  EXPECT_NEAR(mean.wheel_base_m, spec.truth.wheel_base_m, 0.01 * spec.truth.wheel_base_m);
  EXPECT_EQ(dkf.iterations(), static_cast<long>(s.samples.size()));
  // The parameter uncertainty has shrunk well below its prior.
  EXPECT_LT(dkf.estimate().sd_radius_right_m, 0.2 * DualKfParams{}.initial_sd_radius_m);
  // The reported velocity is the calibrated odometry h(θ̂, ω).
  const CalibSample& last = s.samples.back();
  const BodyVelocity v = body_velocity(dkf.estimate().params, last.omega_l_rad_s, last.omega_r_rad_s);
  EXPECT_DOUBLE_EQ(dkf.estimate().velocity.v_m_s, v.v_m_s);
  EXPECT_DOUBLE_EQ(dkf.estimate().velocity.w_rad_s, v.w_rad_s);
}

// Standing still (ω = 0) the odometry carries no information about θ: H = 0,
// so θ̂ stays and P_θ only grows by the random walk Q_θ·dt.
TEST(DualKf, StandingStillOnlyAddsTheRandomWalk) {
  DualKfParams p;
  p.fading_memory = false;  // the paper's random walk
  DualKf dkf(p);
  const DkfParamCov p0 = dkf.param_covariance();
  CalibSample still;
  still.dt_s = 0.5;
  still.v_m_s = 0.05;  // a measurement that the parameters cannot explain anyway
  dkf.step(still);
  EXPECT_EQ(dkf.estimate().params.wheel_radius_right_m, p.initial.wheel_radius_right_m);
  EXPECT_EQ(dkf.estimate().params.wheel_base_m, p.initial.wheel_base_m);
  const double qr = p.radius_walk_m_per_sqrt_s * p.radius_walk_m_per_sqrt_s * 0.5;
  const double qd = p.wheel_base_walk_m_per_sqrt_s * p.wheel_base_walk_m_per_sqrt_s * 0.5;
  EXPECT_NEAR(dkf.param_covariance()(kDkfRadiusRight, kDkfRadiusRight), p0(0, 0) + qr, 1e-18);
  EXPECT_NEAR(dkf.param_covariance()(kDkfRadiusLeft, kDkfRadiusLeft), p0(1, 1) + qr, 1e-18);
  EXPECT_NEAR(dkf.param_covariance()(kDkfWheelBase, kDkfWheelBase), p0(2, 2) + qd, 1e-18);
  EXPECT_EQ(dkf.param_covariance()(0, 1), 0.0);
}

// With fading memory, standing still multiplies P_θ by e^{dt/M}, but never
// past the initial covariance: at the prior it stays there (no wind-up).
TEST(DualKf, FadingMemoryNeverWidensPastThePrior) {
  DualKfParams p;
  DualKf dkf(p);
  const DkfParamCov p0 = dkf.param_covariance();
  CalibSample still;
  still.dt_s = 0.5;
  still.v_m_s = 0.05;
  for (int i = 0; i < 100; ++i) dkf.step(still);
  for (int k = 0; k < kDkfParamDim; ++k) EXPECT_NEAR(dkf.param_covariance()(k, k), p0(k, k), 1e-15 * p0(k, k));
  EXPECT_EQ(dkf.estimate().params.wheel_base_m, p.initial.wheel_base_m);
}

TEST(DualKf, IsValidNamesTheBadField) {
  auto expect_bad = [](DualKfParams p, const std::string& field) {
    std::string why;
    EXPECT_FALSE(p.IsValid(&why)) << field;
    EXPECT_NE(why.find(field), std::string::npos) << why;
    EXPECT_THROW(DualKf{p}, std::invalid_argument) << field;
  };
  std::string why;
  EXPECT_TRUE(DualKfParams{}.IsValid(&why)) << why;
  DualKfParams p;
  p.initial.wheel_base_m = 0.0;
  expect_bad(p, "initial.wheel_base_m = 0");
  p = {};
  p.initial_sd_radius_m = -1.0;
  expect_bad(p, "initial_sd_radius_m = -1");
  p = {};
  p.odometry_sd_w_rad_s = std::numeric_limits<double>::infinity();
  expect_bad(p, "odometry_sd_w_rad_s");
  p = {};
  p.radius_walk_m_per_sqrt_s = -1e-4;
  expect_bad(p, "radius_walk_m_per_sqrt_s");
  p = {};
  p.wheel_base_walk_m_per_sqrt_s = 0.0;  // no walk is allowed
  EXPECT_TRUE(p.IsValid(&why)) << why;
}

TEST(DualKf, RejectsSamplesThatBreakTheContract) {
  DualKf dkf(DualKfParams{});
  CalibSample bad;
  bad.w_var = -1.0;
  EXPECT_THROW(dkf.step(bad), std::invalid_argument);
  bad = {};
  bad.v_m_s = std::nan("");
  EXPECT_THROW(dkf.step(bad), std::invalid_argument);
  EXPECT_EQ(dkf.iterations(), 0);
}

}  // namespace
}  // namespace odotune::filters

// robot_localization's UKF (odotune/filters/rl_ukf.h): its own unit test
// (test/test_ukf.cpp, noetic-devel), the prediction against the EKF's where
// the model is near linear over the points, the correction against the
// Kalman update with ukf.cpp's covariance update, the places it differs from
// the textbook filter, angles across ±π, the gate and the parameters' checks.
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <odotune/filters/rl_ekf.h>
#include <odotune/filters/rl_ukf.h>

namespace rl = odotune::filters::rl;

namespace {

constexpr double kUkfInf = std::numeric_limits<double>::max();

// robot_localization's default process_noise_covariance diagonal.
rl::Cov ukf_default_q() {
  rl::State d;
  d << 0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015;
  return d.asDiagonal();
}

rl::Cov ukf_random_cov(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  rl::Cov a;
  for (int i = 0; i < rl::kStateSize; ++i) {
    for (int j = 0; j < rl::kStateSize; ++j) a(i, j) = u(rng);
  }
  return (a * a.transpose() * 0.1 + rl::Cov::Identity() * 0.01) * scale;
}

rl::State ukf_moving_state() {
  rl::State x = rl::State::Zero();
  x[rl::kX] = 1.0;
  x[rl::kY] = -2.0;
  x[rl::kYaw] = 0.7;
  x[rl::kVx] = 1.2;
  x[rl::kVy] = 0.1;
  x[rl::kVyaw] = 0.4;
  x[rl::kAx] = 0.2;
  return x;
}

rl::RlUkfParams ukf_params(const rl::Cov& Q, const rl::State& x0, const rl::Cov& P0, double alpha = 0.001) {
  rl::RlUkfParams p;
  p.filter.process_noise = Q;
  p.filter.initial_state = x0;
  p.filter.initial_cov = P0;
  p.alpha = alpha;
  return p;
}

rl::Measurement ukf_fix(double x, double y, double var) {
  rl::Measurement m;
  m.z[rl::kX] = x;
  m.z[rl::kY] = y;
  m.R(rl::kX, rl::kX) = var;
  m.R(rl::kY, rl::kY) = var;
  m.mask[rl::kX] = m.mask[rl::kY] = true;
  return m;
}

double ukf_relative(const rl::Cov& a, const rl::Cov& b) { return (a - b).norm() / b.norm(); }

}  // namespace

TEST(RlUkf, WeightsFollowTheScaledUnscentedTransform) {
  const rl::UkfWeights w = rl::ukf_weights(0.001, 0.0, 2.0);
  EXPECT_DOUBLE_EQ(w.lambda, 1e-6 * 15.0 - 15.0);
  double sum = 0.0;
  for (double v : w.state) sum += v;
  EXPECT_NEAR(sum, 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(w.covariance[0], w.state[0] + 1.0 - 1e-6 + 2.0);
  EXPECT_NEAR(w.state[7] * (2.0 * 15.0 * 1e-6), 1.0, 1e-9);  // n + λ = 15 − 15 + 1.5e-5, rounded
  EXPECT_EQ(w.state[7], w.covariance[7]);
}

// test_ukf.cpp: a first measurement of every member (mᵢ = 0.15·i, variances
// 1e-9) becomes the state and the covariance exactly; with P = 0.5·I, a
// second one of 2m two seconds later leaves every member within 0.001 of it.
TEST(RlUkf, ReproducesRobotLocalizationsUkfTest) {
  rl::RlUkf ukf(ukf_params(ukf_default_q(), rl::State::Zero(), rl::Cov::Identity() * 0.5));
  rl::Measurement m;
  for (int i = 0; i < rl::kStateSize; ++i) {
    m.z[i] = i * 0.01 * rl::kStateSize;
    m.R(i, i) = 1e-9;
    m.mask[i] = true;
  }
  m.time_ns = 1000'000'000'000;
  m.mahalanobis_threshold = kUkfInf;
  ASSERT_TRUE(ukf.process(m));
  EXPECT_EQ(ukf.state(), m.z);
  EXPECT_EQ(ukf.cov(), m.R);

  ukf.set_cov(rl::Cov::Identity() * 0.5);
  rl::Measurement m2 = m;
  m2.z *= 2.0;
  m2.time_ns = 1002'000'000'000;
  ASSERT_TRUE(ukf.process(m2));
  for (int i = 0; i < rl::kStateSize; ++i) EXPECT_LT(std::abs(m2.z[i] - ukf.state()[i]), 0.001) << i;
}

// Over points this close, the model is linear: the UKF's prediction is the
// EKF's, x = f(x) and P = J·P·Jᵀ (+ Δt·Q, here zero); the mean differs by
// the second-order term, of the order of P.
TEST(RlUkf, PredictionMatchesTheEkfForASmallCovariance) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    const rl::Cov P0 = ukf_random_cov(rng, 1e-6);
    const rl::State x0 = ukf_moving_state();
    rl::RlUkf ukf(ukf_params(rl::Cov::Zero(), x0, P0));
    rl::RlEkfParams ep;
    ep.process_noise = rl::Cov::Zero();
    ep.initial_state = x0;
    ep.initial_cov = P0;
    rl::RlEkf ekf(ep);
    const double dt = 0.05 + 0.1 * trial;
    ukf.predict(dt);
    ekf.predict(dt);
    EXPECT_LT((ukf.state() - ekf.state()).norm(), 1e-6) << trial;
    EXPECT_LT(ukf_relative(ukf.cov(), ekf.cov()), 2e-3) << trial;
  }
}

// The correction with a linear measurement is the Kalman update, but its
// covariance keeps K·R·Kᵀ more than the EKF's (ukf.cpp subtracts K·P_zz·Kᵀ).
TEST(RlUkf, LinearCorrectionIsTheKalmanUpdateLessKPzzKt) {
  std::mt19937 rng(9);
  const rl::Cov P0 = ukf_random_cov(rng, 0.1);
  const rl::State x0 = ukf_moving_state();
  rl::RlUkf ukf(ukf_params(rl::Cov::Zero(), x0, P0, 1.0));
  ukf.predict(0.0);  // f is the identity over Δt = 0: the points of (x0, P0)
  ASSERT_LT(ukf_relative(ukf.cov(), P0), 1e-12);
  const rl::Cov P = ukf.cov();
  rl::Measurement m = ukf_fix(1.3, -2.4, 0.05);
  m.mahalanobis_threshold = kUkfInf;
  ASSERT_TRUE(ukf.correct(m));

  Eigen::Matrix<double, 2, rl::kStateSize> H = Eigen::Matrix<double, 2, rl::kStateSize>::Zero();
  H(0, rl::kX) = H(1, rl::kY) = 1.0;
  const Eigen::Matrix2d R = Eigen::Matrix2d::Identity() * 0.05, Pzz = H * P * H.transpose();
  const Eigen::Matrix<double, rl::kStateSize, 2> K = P * H.transpose() * (Pzz + R).inverse();
  const Eigen::Vector2d nu(1.3 - x0[rl::kX], -2.4 - x0[rl::kY]);
  EXPECT_LT((ukf.state() - (x0 + K * nu)).norm(), 1e-9);
  EXPECT_LT(ukf_relative(ukf.cov(), P - K * Pzz * K.transpose()), 1e-9);

  rl::RlEkfParams ep;
  ep.initial_state = x0;
  ep.initial_cov = P0;
  rl::RlEkf ekf(ep);
  ASSERT_TRUE(ekf.correct(m));
  EXPECT_LT((ukf.state() - ekf.state()).norm(), 1e-9);
  EXPECT_LT(ukf_relative(ukf.cov() - ekf.cov(), K * R * K.transpose()), 1e-6);
}

// The first correction after a prediction uses the propagated points, which
// Q is not in: its gain, and so the corrected state, do not depend on Q. A
// second correction at the same time draws new points from x and P, which do.
TEST(RlUkf, FirstCorrectionAfterAPredictionUsesPointsWithoutQ) {
  std::mt19937 rng(2);
  const rl::Cov P0 = ukf_random_cov(rng, 0.01);
  rl::RlUkf small(ukf_params(ukf_default_q() * 1e-3, ukf_moving_state(), P0));
  rl::RlUkf large(ukf_params(ukf_default_q() * 10.0, ukf_moving_state(), P0));
  rl::Measurement m = ukf_fix(1.5, -1.8, 0.1);
  m.mahalanobis_threshold = kUkfInf;
  for (rl::RlUkf* f : {&small, &large}) {
    f->predict(0.5);
    ASSERT_TRUE(f->correct(m));
  }
  EXPECT_LT((small.state() - large.state()).norm(), 1e-9);
  EXPECT_GT(ukf_relative(large.cov(), small.cov()), 0.1);  // Q is in P
  const rl::State after_first = small.state();
  for (rl::RlUkf* f : {&small, &large}) ASSERT_TRUE(f->correct(m));
  EXPECT_GT((small.state() - large.state()).norm(), 1e-3);
  EXPECT_GT((small.state() - after_first).norm(), 1e-6);
}

// The mean heading crosses π: atan2 of the weighted sines and cosines gives
// it in (−π, π], and the points' differences from it are wrapped.
TEST(RlUkf, PredictedHeadingCrossesPi) {
  rl::State x = rl::State::Zero();
  x[rl::kYaw] = std::numbers::pi - 0.01;
  x[rl::kVyaw] = 0.2;
  rl::Cov P = rl::Cov::Identity() * 1e-4;
  P(rl::kYaw, rl::kYaw) = 0.01;  // with α = 1 the points reach ±0.39 rad
  rl::RlUkf ukf(ukf_params(rl::Cov::Zero(), x, P, 1.0));
  ukf.predict(0.1);
  EXPECT_NEAR(ukf.state()[rl::kYaw], -std::numbers::pi + 0.01, 1e-9);
  EXPECT_NEAR(ukf.cov()(rl::kYaw, rl::kYaw), 0.01 + 0.1 * 0.1 * 1e-4, 1e-9);
}

// ukf.cpp's heading mean, atan2 of the weighted sines and cosines with
// W₀ ≈ −1/α², points the other way once the yaw variance passes 2 rad²: the
// weighted cosines sum to about 1 − var/2. The filter then turns by π and its
// yaw variance goes negative, as ukf_node's does with a heading nothing
// measures (docs/robot-localization-ukf.md).
TEST(RlUkf, HeadingMeanTurnsByPiOnceItsVarianceExceedsTwo) {
  rl::State x = rl::State::Zero();
  x[rl::kYaw] = 0.5;
  for (double var : {1.9, 2.1}) {
    rl::Cov P = rl::Cov::Identity() * 1e-4;
    P(rl::kYaw, rl::kYaw) = var;
    rl::RlUkf ukf(ukf_params(rl::Cov::Zero(), x, P));
    ukf.predict(0.01);
    if (var < 2.0) {
      EXPECT_NEAR(ukf.state()[rl::kYaw], 0.5, 1e-6);
      EXPECT_GT(ukf.cov()(rl::kYaw, rl::kYaw), 0.0);
    } else {
      EXPECT_NEAR(ukf.state()[rl::kYaw], rl::normalize_angle(0.5 + std::numbers::pi), 1e-6);
      EXPECT_LT(ukf.cov()(rl::kYaw, rl::kYaw), -1.0);
    }
  }
}

TEST(RlUkf, YawInnovationIsWrapped) {
  rl::State x = rl::State::Zero();
  x[rl::kYaw] = 3.0;
  rl::RlUkf ukf(ukf_params(rl::Cov::Zero(), x, rl::Cov::Identity() * 0.1, 1.0));
  ukf.predict(0.0);
  rl::Measurement m;
  m.z[rl::kYaw] = -3.1;  // 0.18 rad from 3.0 across π
  m.R(rl::kYaw, rl::kYaw) = 0.1;
  m.mask[rl::kYaw] = true;
  m.mahalanobis_threshold = kUkfInf;
  ASSERT_TRUE(ukf.correct(m));
  const double expected = 3.0 + 0.5 * (2.0 * std::numbers::pi - 6.1);  // K = 0.5
  EXPECT_NEAR(ukf.state()[rl::kYaw], expected, 1e-6);
}

TEST(RlUkf, MahalanobisGateRejectsAnOutlierAndKeepsTheFilter) {
  rl::RlUkf ukf(ukf_params(ukf_default_q(), ukf_moving_state(), rl::Cov::Identity() * 0.01));
  ukf.predict(0.1);
  const rl::State x = ukf.state();
  const rl::Cov P = ukf.cov();
  rl::Measurement m = ukf_fix(50.0, 50.0, 0.01);
  m.mahalanobis_threshold = 3.0;
  EXPECT_FALSE(ukf.correct(m));
  EXPECT_EQ(ukf.state(), x);
  EXPECT_EQ(ukf.cov(), P);
  m = ukf_fix(x[rl::kX] + 0.05, x[rl::kY], 0.01);
  m.mahalanobis_threshold = 3.0;
  EXPECT_TRUE(ukf.correct(m));
}

TEST(RlUkf, DynamicProcessNoiseLeavesAStandingRobotsPoseVarianceAlone) {
  rl::RlUkfParams p = ukf_params(ukf_default_q(), rl::State::Zero(), rl::Cov::Identity() * 1e-6);
  p.filter.dynamic_process_noise = true;
  rl::RlUkf ukf(p);
  ukf.predict(1.0);
  // Q's pose block scaled by |v|² = 0; x = x + vx·Δt + ax·Δt²/2 and
  // vx = vx + ax·Δt carry their variances.
  EXPECT_NEAR(ukf.cov()(rl::kX, rl::kX), 1e-6 * (1.0 + 1.0 + 0.25), 1e-12);
  EXPECT_NEAR(ukf.cov()(rl::kVx, rl::kVx), 2e-6 + 0.025, 1e-12);
}

TEST(RlUkf, ProcessInitialisesAndDoesNotRewindTime) {
  rl::RlUkf ukf(ukf_params(ukf_default_q(), rl::State::Zero(), rl::Cov::Identity()));
  rl::Measurement m = ukf_fix(2.0, 3.0, 0.5);
  m.time_ns = 5'000'000'000;
  ASSERT_TRUE(ukf.process(m));
  EXPECT_TRUE(ukf.initialized());
  EXPECT_EQ(ukf.state()[rl::kX], 2.0);
  EXPECT_EQ(ukf.cov()(rl::kY, rl::kY), 0.5);
  m.time_ns = 4'000'000'000;  // late: corrected, not predicted, the clock kept
  ukf.process(m);
  EXPECT_EQ(ukf.last_time_ns(), 5'000'000'000);
}

TEST(RlUkf, ParametersAreChecked) {
  std::string why;
  rl::RlUkfParams p;
  EXPECT_TRUE(p.IsValid(&why)) << why;
  p.alpha = 0.0;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("alpha"), std::string::npos);
  p = rl::RlUkfParams{};
  p.kappa = -15.0;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("kappa"), std::string::npos);
  p = rl::RlUkfParams{};
  p.beta = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("beta"), std::string::npos);
  p = rl::RlUkfParams{};
  p.alpha = -1.0;
  EXPECT_THROW(rl::RlUkf{p}, std::invalid_argument);
}

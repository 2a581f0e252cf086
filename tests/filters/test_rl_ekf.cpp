// robot_localization's EKF (filters/rl_ekf.h): the motion model's Jacobian
// against finite differences, the sparse predict and the subset correction
// against a literal dense implementation of ekf.cpp's equations, and the
// filter's behaviour on a standing robot, masks, gating, initialisation and
// angles.
#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "filters/rl_ekf.h"

namespace rl = odotune::filters::rl;

namespace {

rl::State random_state(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  rl::State x;
  for (int i = 0; i < rl::kStateSize; ++i) x[i] = u(rng);
  x[rl::kPitch] *= 1.2;  // away from ±π/2
  x[rl::kYaw] *= 3.0;
  return x;
}

rl::Cov random_cov(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  rl::Cov a;
  for (int i = 0; i < rl::kStateSize; ++i) {
    for (int j = 0; j < rl::kStateSize; ++j) a(i, j) = u(rng);
  }
  return a * a.transpose() * 0.1 + rl::Cov::Identity() * 0.01;
}

rl::Cov default_q() {
  rl::State d;
  d << 0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015;
  return d.asDiagonal();
}

// f(x) = A(x)·x with the angles wrapped, as the filter's predict applies it.
rl::State propagate(const rl::State& x, double dt) { return rl::transition(x, dt).A * x; }

}  // namespace

TEST(RlEkf, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const rl::State x = random_state(rng);
    const double dt = 0.05 + 0.05 * trial;
    const rl::Cov J = rl::transition(x, dt).J;
    const double h = 1e-6;
    for (int c = 0; c < rl::kStateSize; ++c) {
      rl::State xp = x, xm = x;
      xp[c] += h;
      xm[c] -= h;
      const rl::State col = (propagate(xp, dt) - propagate(xm, dt)) / (2.0 * h);
      for (int r = 0; r < rl::kStateSize; ++r) {
        EXPECT_NEAR(J(r, c), col[r], 1e-7 * (1.0 + std::abs(col[r])))
            << "trial " << trial << " J(" << r << "," << c << ")";
      }
    }
  }
}

TEST(RlEkf, ModelMovesAlongTheHeading) {
  rl::State x = rl::State::Zero();
  x[rl::kYaw] = std::numbers::pi / 2;
  x[rl::kVx] = 2.0;
  x[rl::kAx] = 1.0;
  x[rl::kVyaw] = 0.3;
  const rl::State y = propagate(x, 0.5);
  EXPECT_NEAR(y[rl::kX], 0.0, 1e-12);
  EXPECT_NEAR(y[rl::kY], 2.0 * 0.5 + 0.5 * 1.0 * 0.25, 1e-12);
  EXPECT_NEAR(y[rl::kVx], 2.5, 1e-12);
  EXPECT_NEAR(y[rl::kYaw], std::numbers::pi / 2 + 0.15, 1e-12);
}

// The sparse J·P·Jᵀ and the subset Joseph correction against the dense
// matrices of ekf.cpp: P ← J·P·Jᵀ + Δt·Q and (I − K·H)·P·(I − K·H)ᵀ + K·R·Kᵀ.
TEST(RlEkf, MatchesDenseEquations) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 30; ++trial) {
    rl::RlEkfParams params;
    params.process_noise = default_q();
    params.initial_cov = random_cov(rng);
    params.initial_state = random_state(rng);
    params.dynamic_process_noise = trial % 2 == 1;
    rl::RlEkf f(params);
    const double dt = 0.02 * (trial + 1);
    f.predict(dt);

    const rl::State x0 = params.initial_state;
    const rl::Transition t = rl::transition(x0, dt);
    rl::Cov Q = params.process_noise;
    if (params.dynamic_process_noise) Q.topLeftCorner<6, 6>() *= x0.segment<6>(rl::kVx).squaredNorm();
    const rl::Cov P_pred = t.J * params.initial_cov * t.J.transpose() + dt * Q;
    rl::State x_pred = t.A * x0;
    for (int a : {rl::kRoll, rl::kPitch, rl::kYaw}) x_pred[a] = rl::normalize_angle(x_pred[a]);
    ASSERT_LT((f.state() - x_pred).norm(), 1e-12);
    ASSERT_LT((f.cov() - P_pred).norm(), 1e-12 * P_pred.norm());

    rl::Measurement m;
    m.z = random_state(rng);
    const rl::Cov Rm = random_cov(rng);
    m.R = Rm;
    std::vector<int> idx;
    for (int i = 0; i < rl::kStateSize; ++i) {
      m.mask[i] = (i * 7 + trial) % 3 != 0;
      if (m.mask[i]) idx.push_back(i);
    }
    ASSERT_TRUE(f.correct(m));
    const int n = static_cast<int>(idx.size());
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, rl::kStateSize), R(n, n);
    Eigen::VectorXd nu(n);
    for (int i = 0; i < n; ++i) {
      H(i, idx[i]) = 1.0;
      nu[i] = m.z[idx[i]] - x_pred[idx[i]];
      if (idx[i] >= rl::kRoll && idx[i] <= rl::kYaw) nu[i] = rl::normalize_angle(nu[i]);
      for (int j = 0; j < n; ++j) R(i, j) = Rm(idx[i], idx[j]);
    }
    const Eigen::MatrixXd K = P_pred * H.transpose() * (H * P_pred * H.transpose() + R).inverse();
    const Eigen::MatrixXd G = Eigen::MatrixXd::Identity(rl::kStateSize, rl::kStateSize) - K * H;
    const Eigen::MatrixXd P_new = G * P_pred * G.transpose() + K * R * K.transpose();
    rl::State x_new = x_pred + K * nu;
    for (int a : {rl::kRoll, rl::kPitch, rl::kYaw}) x_new[a] = rl::normalize_angle(x_new[a]);
    EXPECT_LT((f.state() - x_new).norm(), 1e-10) << "trial " << trial;
    EXPECT_LT((f.cov() - P_new).norm(), 1e-10 * P_new.norm()) << "trial " << trial;
  }
}

// A robot that stands still, measured as still by its wheels: the state stays
// at zero and the unmeasured position's variance grows as Q·t.
TEST(RlEkf, StandingRobotStaysAndItsPositionVarianceGrowsLinearly) {
  rl::RlEkfParams params;
  params.process_noise = default_q();
  rl::RlEkf f(params);
  rl::Measurement m;
  m.R = rl::Cov::Identity() * 1e-4;
  for (int i = rl::kVx; i <= rl::kVyaw; ++i) m.mask[i] = true;
  const std::int64_t step_ns = 100'000'000;
  for (int k = 0; k <= 600; ++k) {
    m.time_ns = k * step_ns;
    ASSERT_TRUE(f.process(m));
  }
  EXPECT_EQ(f.last_time_ns(), 600 * step_ns);
  EXPECT_LT(f.state().norm(), 1e-12);
  EXPECT_NEAR(f.cov()(rl::kX, rl::kX), 0.05 * 60.0, 0.05 * 60.0 * 0.01);
  EXPECT_NEAR(f.cov()(rl::kYaw, rl::kYaw), 0.06 * 60.0, 0.06 * 60.0 * 0.01);
  EXPECT_LT(f.cov()(rl::kVx, rl::kVx), 1e-3);  // measured: bounded
}

TEST(RlEkf, FirstMeasurementInitialisesOnlyItsMembers) {
  rl::RlEkf f(rl::RlEkfParams{});
  rl::Measurement m;
  m.time_ns = 5;
  m.z[rl::kX] = 3.0;
  m.z[rl::kY] = 4.0;
  m.z[rl::kVx] = 9.0;  // not in the mask
  m.R(rl::kX, rl::kX) = 0.5;
  m.R(rl::kY, rl::kY) = 0.7;
  m.R(rl::kX, rl::kY) = m.R(rl::kY, rl::kX) = 0.1;
  m.mask[rl::kX] = m.mask[rl::kY] = true;
  EXPECT_FALSE(f.initialized());
  f.process(m);
  EXPECT_TRUE(f.initialized());
  EXPECT_EQ(f.state()[rl::kX], 3.0);
  EXPECT_EQ(f.state()[rl::kY], 4.0);
  EXPECT_EQ(f.state()[rl::kVx], 0.0);
  EXPECT_EQ(f.cov()(rl::kX, rl::kY), 0.1);
  EXPECT_EQ(f.cov()(rl::kVx, rl::kVx), 1e-9);
  EXPECT_EQ(f.last_time_ns(), 5);
}

TEST(RlEkf, MaskedMeasurementChangesOnlyCorrelatedMembers) {
  rl::RlEkfParams params;
  params.initial_cov = rl::Cov::Identity();
  rl::RlEkf f(params);
  rl::Measurement m;
  m.z[rl::kVx] = 1.0;
  m.z[rl::kY] = 5.0;  // present in z but not fused
  m.R = rl::Cov::Identity();
  m.mask[rl::kVx] = true;
  ASSERT_TRUE(f.correct(m));
  EXPECT_NEAR(f.state()[rl::kVx], 0.5, 1e-12);  // equal variances: halfway
  EXPECT_EQ(f.state()[rl::kY], 0.0);
  EXPECT_NEAR(f.cov()(rl::kVx, rl::kVx), 0.5, 1e-12);
  EXPECT_EQ(f.cov()(rl::kY, rl::kY), 1.0);
}

TEST(RlEkf, MahalanobisGateRejectsAnOutlierAndKeepsTheState) {
  rl::RlEkfParams params;
  params.initial_cov = rl::Cov::Identity() * 0.01;
  rl::RlEkf f(params);
  rl::Measurement m;
  m.R = rl::Cov::Identity() * 0.01;
  m.mask[rl::kX] = true;
  m.z[rl::kX] = 1.0;  // innovation 1 m, S = 0.02 m²: 7.1 σ
  m.mahalanobis_threshold = 5.0;
  EXPECT_FALSE(f.correct(m));
  EXPECT_EQ(f.state()[rl::kX], 0.0);
  m.mahalanobis_threshold = 8.0;
  EXPECT_TRUE(f.correct(m));
  EXPECT_NEAR(f.state()[rl::kX], 0.5, 1e-12);
}

TEST(RlEkf, YawInnovationIsWrapped) {
  rl::RlEkfParams params;
  params.initial_state[rl::kYaw] = -3.1;
  params.initial_cov = rl::Cov::Identity();
  rl::RlEkf f(params);
  rl::Measurement m;
  m.R = rl::Cov::Identity();
  m.mask[rl::kYaw] = true;
  m.z[rl::kYaw] = 3.1;  // 0.083 rad away across ±π, not 6.2 rad
  ASSERT_TRUE(f.correct(m));
  const double expected = rl::normalize_angle(-3.1 - 0.5 * (2 * std::numbers::pi - 6.2));
  EXPECT_NEAR(f.state()[rl::kYaw], expected, 1e-12);
  EXPECT_LE(std::abs(f.state()[rl::kYaw]), std::numbers::pi);
}

TEST(RlEkf, NonFiniteMembersAreLeftOutAndLateMeasurementsDoNotRewindTime) {
  rl::RlEkfParams params;
  params.initial_cov = rl::Cov::Identity();
  rl::RlEkf f(params);
  rl::Measurement m;
  m.R = rl::Cov::Identity();
  m.mask[rl::kX] = m.mask[rl::kY] = true;
  m.time_ns = 1'000'000'000;
  f.process(m);  // initialises
  m.z[rl::kX] = std::nan("");
  m.z[rl::kY] = 2.0;
  m.time_ns = 500'000'000;  // earlier: corrected without a prediction
  ASSERT_TRUE(f.process(m));
  EXPECT_EQ(f.state()[rl::kX], 0.0);
  EXPECT_GT(f.state()[rl::kY], 0.0);
  EXPECT_EQ(f.last_time_ns(), 1'000'000'000);
}

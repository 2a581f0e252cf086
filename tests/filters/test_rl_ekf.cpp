// robot_localization's EKF (odotune/filters/rl_ekf.h): the motion model's Jacobian
// against finite differences, the sparse predict and the subset correction
// against a literal dense implementation of ekf.cpp's equations, the
// filter's behaviour on a standing robot, masks, gating, initialisation and
// angles, and RlEkfLanes against one RlEkf per lane, to the bit.
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <odotune/filters/rl_ekf.h>

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

// The bits of the fmod formula angles::normalize_angle is, for every kind of
// input (the filter's shortcut computes fmod's exact remainder otherwise).
// robot_localization's test_ekf.cpp: a first measurement of every member
// (mᵢ = 0.15·i, variances 1e-9) becomes the state and the covariance exactly;
// with P = 0.5·I, a second one of 2m two seconds later leaves every member
// within 0.001 of it.
TEST(RlEkf, ReproducesRobotLocalizationsEkfTest) {
  rl::RlEkfParams params;
  params.process_noise = default_q();
  params.initial_cov = rl::Cov::Identity() * 0.5;
  rl::RlEkf ekf(params);
  rl::Measurement m;
  for (int i = 0; i < rl::kStateSize; ++i) {
    m.z[i] = i * 0.01 * rl::kStateSize;
    m.R(i, i) = 1e-9;
    m.mask[i] = true;
  }
  m.time_ns = 1000'000'000'000;
  ASSERT_TRUE(ekf.process(m));
  EXPECT_EQ(ekf.state(), m.z);
  EXPECT_EQ(ekf.cov(), m.R);
  ekf.restore(ekf.state(), rl::Cov::Identity() * 0.5, ekf.last_time_ns());  // setEstimateErrorCovariance
  rl::Measurement m2 = m;
  m2.z *= 2.0;
  m2.time_ns = 1002'000'000'000;
  ASSERT_TRUE(ekf.process(m2));
  for (int i = 0; i < rl::kStateSize; ++i) EXPECT_LT(std::abs(m2.z[i] - ekf.state()[i]), 0.001) << i;
}

TEST(RlEkf, NormalizeAngleGivesTheBitsOfFmod) {
  auto by_fmod = [](double a) {
    const double r = std::fmod(a + std::numbers::pi, 2.0 * std::numbers::pi);
    return r <= 0.0 ? r + std::numbers::pi : r - std::numbers::pi;
  };
  std::vector<double> values = {0.0,
                                -0.0,
                                std::nan(""),
                                std::numeric_limits<double>::infinity(),
                                -std::numeric_limits<double>::infinity(),
                                1e300,
                                -1e300};
  for (int k = -6; k <= 6; ++k) {
    const double a = k * std::numbers::pi;
    for (double b : {a, std::nextafter(a, 1e9), std::nextafter(a, -1e9), a - std::numbers::pi, a + 0.5}) {
      values.push_back(b);
    }
  }
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  for (int k = 0; k < 10000; ++k) values.push_back(u(rng));
  for (double a : values) {
    const double got = rl::normalize_angle(a), want = by_fmod(a);
    EXPECT_EQ(std::memcmp(&got, &want, sizeof got), 0) << a << ": " << got << " against " << want;
  }
}

namespace {

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// Lane l's filter of a lane test: its own noise, start and dynamic flag.
rl::RlEkfParams lane_params(std::mt19937& rng, int l) {
  rl::RlEkfParams p;
  p.process_noise = default_q() * (0.5 + 0.3 * l);
  p.process_noise(rl::kX, rl::kY) = p.process_noise(rl::kY, rl::kX) = 0.001 * l;
  p.initial_cov = random_cov(rng);
  p.initial_state = random_state(rng);
  p.dynamic_process_noise = l % 3 == 1;
  return p;
}

// A measurement of `mask` at `t_ns` with lane-dependent values.
rl::Measurement lane_measurement(std::mt19937& rng, const rl::Mask& mask, std::int64_t t_ns) {
  rl::Measurement m;
  m.time_ns = t_ns;
  m.mask = mask;
  m.z = random_state(rng);
  m.R = random_cov(rng) * 0.1;
  m.R(0, 0) = -m.R(0, 0);  // taken by its magnitude
  m.mahalanobis_threshold = std::uniform_real_distribution<double>(1.0, 6.0)(rng);
  return m;
}

// Every lane of RlEkfLanes against an RlEkf with its parameters fed its
// measurements, to the bit: masks of 1 to 15 members, repeated and earlier
// stamps, gating that rejects in some lanes only, a value that is nan in one
// lane only, timeout predictions.
void expect_lanes_are_single_filters(int lanes, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<rl::RlEkfParams> params;
  for (int l = 0; l < lanes; ++l) params.push_back(lane_params(rng, l));
  rl::RlEkfLanes batch(params);
  std::vector<rl::RlEkf> single(params.begin(), params.end());
  ASSERT_EQ(batch.lanes(), lanes);
  std::int64_t t = 1'000'000'000;
  int rejected = 0, accepted = 0;
  for (int step = 0; step < 120; ++step) {
    rl::Mask mask{};
    const int members = 1 + step % rl::kStateSize;
    for (int i = 0; i < members; ++i) mask[(i * 7 + step) % rl::kStateSize] = true;
    t += step % 5 == 0 ? 0 : (step % 11 == 0 ? -20'000'000 : 30'000'000);
    if (step % 13 == 7) {
      t += 100'000'000;
      batch.predict_to(t);
      for (rl::RlEkf& f : single) f.predict_to(t);
    }
    std::vector<rl::Measurement> ms;
    for (int l = 0; l < lanes; ++l) ms.push_back(lane_measurement(rng, mask, t));
    if (step % 17 == 9) ms[lanes / 2].z[(step * 7) % rl::kStateSize] = std::nan("");
    const std::uint32_t bits = batch.process(ms);
    for (int l = 0; l < lanes; ++l) {
      const bool ok = single[l].process(ms[l]);
      EXPECT_EQ((bits >> l & 1u) != 0, ok) << "step " << step << " lane " << l;
      (ok ? accepted : rejected) += 1;
      ASSERT_TRUE(same_bits(batch.state(l), single[l].state())) << "step " << step << " lane " << l;
      ASSERT_TRUE(same_bits(batch.cov(l), single[l].cov())) << "step " << step << " lane " << l;
    }
    EXPECT_EQ(batch.last_time_ns(), single[0].last_time_ns());
  }
  EXPECT_GT(accepted, 0);
  EXPECT_GT(rejected, 0);
}

}  // namespace

TEST(RlEkfLanes, EachLaneIsItsOwnRlEkf) {
  expect_lanes_are_single_filters(rl::kLanes, 21);
  expect_lanes_are_single_filters(3, 22);
  expect_lanes_are_single_filters(1, 23);
}

TEST(RlEkf, CovarianceStaysExactlySymmetric) {
  std::mt19937 rng(8);
  rl::RlEkf f(lane_params(rng, 1));
  for (int step = 0; step < 50; ++step) {
    rl::Mask mask{};
    for (int i = 0; i <= step % 6; ++i) mask[(i * 4 + step) % rl::kStateSize] = true;
    f.process(lane_measurement(rng, mask, 1'000'000'000 + step * 25'000'000LL));
    ASSERT_TRUE(same_bits(f.cov(), f.cov().transpose().eval())) << "step " << step;
  }
}

TEST(RlEkfLanes, RefusesAnotherLaneCount) {
  EXPECT_THROW(rl::RlEkfLanes(std::vector<rl::RlEkfParams>{}), std::invalid_argument);
  EXPECT_THROW(rl::RlEkfLanes(std::vector<rl::RlEkfParams>(rl::kLanes + 1)), std::invalid_argument);
  EXPECT_THROW(rl::RlEkfLanes(std::vector<rl::RlEkfParams>(2)).process(std::vector<rl::Measurement>(3)),
               std::invalid_argument);
}

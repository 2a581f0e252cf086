// EKF maths: Jacobians against numerical differentiation, the update against
// its closed form, divergence detection, and the segment-batched form against
// the step-by-step filter.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/core/planar_motion.h>
#include <odotune/filters/diff_drive.h>
#include <odotune/filters/ekf.h>
#include <odotune/filters/ekf_noise.h>
#include <odotune/filters/ekf_segments.h>

namespace odotune::filters {
namespace {

constexpr double kBase = 0.31;

// Central differences of diff_drive_step w.r.t. pose and control.
TEST(DiffDrive, JacobiansMatchNumericalDifferentiation) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Pose x(U(rng) * 5, U(rng) * 5, U(rng) * 4);
    WheelTravel u{0.05 * U(rng), 0.05 * U(rng)};
    const MotionStep s = diff_drive_step(x, u, kBase);
    const double h = 1e-6;
    for (int j = 0; j < kStateDim; ++j) {
      Pose xp = x, xm = x;
      xp(j) += h;
      xm(j) -= h;
      const Pose num = (diff_drive_step(xp, u, kBase).next - diff_drive_step(xm, u, kBase).next) / (2 * h);
      for (int i = 0; i < kStateDim; ++i) EXPECT_NEAR(s.F(i, j), num(i), 1e-8) << i << "," << j;
    }
    for (int j = 0; j < kControlDim; ++j) {
      WheelTravel up = u, um = u;
      (j == kLeft ? up.left_m : up.right_m) += h;
      (j == kLeft ? um.left_m : um.right_m) -= h;
      const Pose num = (diff_drive_step(x, up, kBase).next - diff_drive_step(x, um, kBase).next) / (2 * h);
      for (int i = 0; i < kStateDim; ++i) EXPECT_NEAR(s.V(i, j), num(i), 1e-8) << i << "," << j;
    }
  }
}

TEST(DiffDrive, StraightAndSpinGeometry) {
  const MotionStep straight = diff_drive_step(Pose(1, 2, M_PI / 2), {0.1, 0.1}, kBase);
  EXPECT_NEAR(straight.next(kX), 1.0, 1e-12);
  EXPECT_NEAR(straight.next(kY), 2.1, 1e-12);
  const MotionStep spin = diff_drive_step(Pose(0, 0, 0), {-0.05, 0.05}, kBase);
  EXPECT_NEAR(spin.next(kTheta), 0.1 / kBase, 1e-12);
  EXPECT_NEAR(spin.next.head<2>().norm(), 0.0, 1e-12);
}

// The EKF's step and the one dead reckoning every fit walks
// (odotune/core/planar_motion.h) give the same pose to the bit.
TEST(DiffDrive, PoseIsCoreMidpointAdvanceBitForBit) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    const Pose x(U(rng) * 50, U(rng) * 50, U(rng) * 7);
    const WheelTravel u{0.2 * U(rng), 0.2 * U(rng)};
    const double base = 0.3 + 0.2 * U(rng);
    const Pose next = diff_drive_step(x, u, base).next;
    double px = x(kX), py = x(kY), th = x(kTheta);
    core::midpoint_advance(&px, &py, &th, u.left_m, u.right_m, base);
    EXPECT_EQ(next(kX), px);
    EXPECT_EQ(next(kY), py);
    EXPECT_EQ(next(kTheta), th);
  }
}

// The arc step is exact for constant velocities: a full circle of radius
// v/w comes back to its start, and straight travel moves along the heading.
TEST(PlanarMotion, ArcStepClosesACircleAndSincIsSmooth) {
  const double v = 0.7, w = 0.35, h = 0.5;
  const int n = static_cast<int>(std::lround(2 * M_PI / (w * h)));
  const double hh = 2 * M_PI / (w * n);  // steps that close the circle exactly
  double x = 1, y = -2, th = 0.3;
  for (int k = 0; k < n; ++k) {
    const double half = 0.5 * w * hh;
    core::arc_advance(&x, &y, &th, half, core::sinc(half) * hh, v, 0.0, w * hh);
  }
  EXPECT_NEAR(x, 1.0, 1e-9);
  EXPECT_NEAR(y, -2.0, 1e-9);
  double sx = 0, sy = 0, sth = M_PI / 2;
  core::arc_advance(&sx, &sy, &sth, 0.0, 1.0, 2.0, 0.0, 0.0);
  EXPECT_NEAR(sx, 0.0, 1e-15);
  EXPECT_NEAR(sy, 2.0, 1e-15);
  for (double u : {1e-6, 9.9e-5, 1.01e-4, 1e-3}) EXPECT_NEAR(core::sinc(u), std::sin(u) / u, 1e-15) << u;
  EXPECT_EQ(core::sinc(0.0), 1.0);
}

TEST(EkfNoise, WheelVariancesFollowEquations3To7) {
  NoiseParams p;
  p.model = NoiseModel::gyro;
  p.a1 = 0.1;
  p.a2 = 0.2;
  p.b1 = 0.5;
  p.b2 = 1.0;
  double vl = 0, vr = 0;
  wheel_variances(p, {0.02, 0.03}, 0.4, &vl, &vr);
  const double alpha1 = 0.1 + 0.5 * 0.4, alpha2 = 0.2 + 1.0 * 0.4;
  EXPECT_DOUBLE_EQ(vl, std::pow(alpha1 * 0.02, 2) + std::pow(alpha2 * -0.01, 2));
  EXPECT_DOUBLE_EQ(vr, std::pow(alpha1 * 0.03, 2) + std::pow(alpha2 * -0.01, 2));
}

TEST(EkfNoise, InvalidParamsNameTheBadValue) {
  NoiseParams p;
  p.a1 = -1;
  std::string why;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("a1"), std::string::npos);
  p = NoiseParams{};
  p.q_y_m2 = 0;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("q_y_m2"), std::string::npos);
  p = NoiseParams{};
  p.b2 = 0.3;  // alpha model has no gyro term
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("b2"), std::string::npos);
  EkfParams e;
  e.wheel_base_m = 0;
  EXPECT_FALSE(e.IsValid(&why));
  EXPECT_NE(why.find("wheel_base_m"), std::string::npos);
  EXPECT_THROW(Ekf{e}, std::invalid_argument);
}

TEST(Ekf, UpdateMatchesClosedForm) {
  EkfParams params;
  params.noise.q_x_m2 = 0.04;
  params.noise.q_y_m2 = 0.09;
  params.initial_cov = Pose(0.01, 0.02, 0.03).asDiagonal();
  Ekf ekf(params);
  ekf.update(Position(1.0, -1.0));
  // Diagonal P and H = [I 0]: each coordinate is a scalar Kalman update.
  EXPECT_NEAR(ekf.pose()(kX), 0.01 / (0.01 + 0.04) * 1.0, 1e-12);
  EXPECT_NEAR(ekf.pose()(kY), 0.02 / (0.02 + 0.09) * -1.0, 1e-12);
  EXPECT_NEAR(ekf.pose()(kTheta), 0.0, 1e-12);
  EXPECT_NEAR(ekf.cov()(kX, kX), 0.01 * 0.04 / 0.05, 1e-12);
  EXPECT_NEAR(ekf.cov()(kTheta, kTheta), 0.03, 1e-12);
  EXPECT_EQ(ekf.check(), Divergence::none);
}

TEST(Ekf, PredictGrowsCovarianceByRq) {
  EkfParams params;
  params.noise.model = NoiseModel::rq;
  params.noise.r_x_m2 = 1e-4;
  params.noise.r_y_m2 = 2e-4;
  params.noise.r_theta_rad2 = 1e-3;
  Ekf ekf(params);
  const StateCov P0 = ekf.cov();
  ekf.predict({0.0, 0.0}, 0.0);  // standing still: F = I
  EXPECT_NEAR(ekf.cov()(kX, kX) - P0(kX, kX), 1e-4, 1e-15);
  EXPECT_NEAR(ekf.cov()(kY, kY) - P0(kY, kY), 2e-4, 1e-15);
  EXPECT_NEAR(ekf.cov()(kTheta, kTheta) - P0(kTheta, kTheta), 1e-3, 1e-15);
}

TEST(Ekf, DetectsNonFiniteState) {
  EkfParams params;
  Ekf ekf(params);
  ekf.predict({std::nan(""), 0.1}, 0.0);
  EXPECT_EQ(ekf.check(), Divergence::non_finite);
}

TEST(Ekf, PositiveDefiniteCheck) {
  EXPECT_TRUE(is_positive_definite(StateCov::Identity()));
  StateCov P = StateCov::Identity();
  P(0, 1) = P(1, 0) = 1.5;  // leading 2×2 minor negative
  EXPECT_FALSE(is_positive_definite(P));
  P = StateCov::Identity();
  P(2, 2) = 0.0;
  EXPECT_FALSE(is_positive_definite(P));
}

// A random segment of wheel steps (gentle, with turns) and gyro rates.
struct RandomSegment {
  std::vector<WheelTravel> steps;
  std::vector<double> yaw;
};
RandomSegment random_segment(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  RandomSegment s;
  for (int j = 0; j < n; ++j) {
    const double d = 0.01 + 0.004 * U(rng);
    const double turn = 0.003 * U(rng);
    s.steps.push_back({d - turn, d + turn});
    s.yaw.push_back(std::abs(U(rng)) * 1.5);
  }
  return s;
}

NoiseParams noise_for(NoiseModel m) {
  NoiseParams p;
  p.model = m;
  p.q_x_m2 = 0.0036;
  p.q_y_m2 = 0.0025;
  if (m == NoiseModel::rq) {
    p.r_x_m2 = 3e-6;
    p.r_y_m2 = 7e-6;
    p.r_theta_rad2 = 2e-5;
  } else {
    p.a1 = 0.07;
    p.a2 = 0.3;
    if (m == NoiseModel::gyro) {
      p.b1 = 0.4;
      p.b2 = 1.3;
    }
  }
  return p;
}

class SegmentEquivalence : public ::testing::TestWithParam<NoiseModel> {};

// advance_segment must equal n × Ekf::predict followed by Ekf::update.
TEST_P(SegmentEquivalence, MatchesStepByStepFilter) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const NoiseParams noise = noise_for(GetParam());
  EkfParams params;
  params.noise = noise;
  params.wheel_base_m = kBase;
  params.initial_pose = Pose(1.0, -2.0, 0.7);
  Ekf ekf(params);
  Pose x = params.initial_pose;
  StateCov P = params.initial_cov;
  for (int seg = 0; seg < 30; ++seg) {
    const RandomSegment s = random_segment(rng, 20 + seg % 50);
    std::vector<double> px(s.steps.size()), py(s.steps.size());
    const SegmentMoments m = reduce_segment(s.steps, s.yaw, kBase, px, py);
    // The recorded path, rotated into the world, is the filter's mean.
    const double c = std::cos(x(kTheta)), sn = std::sin(x(kTheta));
    for (std::size_t j = 0; j < s.steps.size(); ++j) {
      ekf.predict(s.steps[j], s.yaw[j]);
      EXPECT_NEAR(ekf.pose()(kX), x(kX) + c * px[j] - sn * py[j], 1e-10);
      EXPECT_NEAR(ekf.pose()(kY), x(kY) + sn * px[j] + c * py[j], 1e-10);
    }
    const StateCov Ppred = predict_segment_cov(noise, m, x(kTheta), P);
    EXPECT_LT((Ppred - ekf.cov()).norm(), 1e-10 * (1.0 + ekf.cov().norm())) << "segment " << seg;
    const Position z = ekf.pose().head<2>() + Position(0.05 * U(rng), 0.05 * U(rng));
    ekf.update(z);
    ASSERT_EQ(advance_segment(noise, m, z, &x, &P), Divergence::none);
    EXPECT_LT((x - ekf.pose()).norm(), 1e-9) << "segment " << seg;
    EXPECT_LT((P - ekf.cov()).norm(), 1e-10 * (1.0 + ekf.cov().norm())) << "segment " << seg;
  }
}

INSTANTIATE_TEST_SUITE_P(AllModels, SegmentEquivalence,
                         ::testing::Values(NoiseModel::rq, NoiseModel::alpha, NoiseModel::gyro),
                         [](const auto& p) { return std::string(to_string(p.param)); });

TEST(Segments, EmptySegmentIsPureUpdate) {
  const NoiseParams noise = noise_for(NoiseModel::alpha);
  EkfParams params;
  params.noise = noise;
  Ekf ekf(params);
  Pose x = params.initial_pose;
  StateCov P = params.initial_cov;
  const SegmentMoments m = reduce_segment({}, {}, kBase);
  ekf.update(Position(0.1, 0.2));
  ASSERT_EQ(advance_segment(noise, m, Position(0.1, 0.2), &x, &P), Divergence::none);
  EXPECT_LT((x - ekf.pose()).norm(), 1e-14);
  EXPECT_LT((P - ekf.cov()).norm(), 1e-14);
}

}  // namespace
}  // namespace odotune::filters

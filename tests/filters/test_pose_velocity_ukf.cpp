// The pose-velocity UKF (odotune/filters/pose_velocity_ukf.h): the prediction's mean
// against the unicycle model and, for a small covariance, its covariance
// against the model's Jacobian propagated by hand (P' = F P Fᵀ + Q); a
// measurement update against the Kalman update written here; fixes pulling
// a drifting pose back; parameter checks and health on bad input.
#include <gtest/gtest.h>

#include <Eigen/LU>  // inverse()
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <odotune/filters/pose_velocity_ukf.h>

namespace odotune::filters {
namespace {

PoseUkfParams params_at(const PoseVelocity& x, double sd) {
  PoseUkfParams p;
  p.initial_state = x;
  p.initial_cov = PoseVelocityCov::Identity() * sd * sd;
  p.q_v_m2_s3 = p.q_w_rad2_s3 = p.q_xy_m2_s = 0.0;
  return p;
}

TEST(PoseVelocityUkf, PredictionFollowsTheUnicycleAndItsJacobian) {
  PoseVelocity x0;
  x0 << 1.0, -2.0, 0.3, 0.8, 0.5;
  const double dt = 0.1, sd = 1e-4;
  PoseVelocityUkf f(params_at(x0, sd));
  f.predict(dt);
  // The mean of the transformed points: the model at the mean up to the
  // curvature term, O(sd²).
  const double mid = 0.3 + 0.5 * 0.5 * dt;
  EXPECT_NEAR(f.state()(kPx), 1.0 + 0.8 * dt * std::cos(mid), 1e-8);
  EXPECT_NEAR(f.state()(kPy), -2.0 + 0.8 * dt * std::sin(mid), 1e-8);
  EXPECT_NEAR(f.state()(kPtheta), 0.3 + 0.5 * dt, 1e-12);
  EXPECT_NEAR(f.state()(kPv), 0.8, 1e-12);
  // F = ∂f/∂x of the model at x0, by central differences of the model.
  auto model = [dt](const PoseVelocity& s) {
    PoseVelocity n = s;
    const double m = s(kPtheta) + 0.5 * s(kPw) * dt;
    n(kPx) += s(kPv) * dt * std::cos(m);
    n(kPy) += s(kPv) * dt * std::sin(m);
    n(kPtheta) += s(kPw) * dt;
    return n;
  };
  PoseVelocityCov F;
  for (int j = 0; j < 5; ++j) {
    PoseVelocity a = x0, b = x0;
    a(j) += 1e-6;
    b(j) -= 1e-6;
    F.col(j) = (model(a) - model(b)) / 2e-6;
  }
  const PoseVelocityCov expected = F * (PoseVelocityCov::Identity() * sd * sd) * F.transpose();
  EXPECT_LT((f.cov() - expected).norm(), 1e-6 * expected.norm());
}

TEST(PoseVelocityUkf, UpdatesAreTheKalmanUpdate) {
  PoseUkfParams p;
  p.initial_state << 0.5, 0.2, -0.1, 0.4, 0.05;
  Eigen::Matrix<double, 5, 5> A;
  A << 2, 0.1, 0, 0.3, 0, 0.1, 1, 0.2, 0, 0.1, 0, 0.2, 1.5, 0, 0, 0.3, 0, 0, 1, 0.2, 0, 0.1, 0, 0.2, 0.8;
  p.initial_cov = 0.01 * A * A.transpose();
  PoseVelocityUkf f(p);
  const Eigen::Matrix2d R = Eigen::Vector2d(0.04, 0.09).asDiagonal();
  f.update_position(0.7, 0.1, R);
  Eigen::Matrix<double, 2, 5> H = Eigen::Matrix<double, 2, 5>::Zero();
  H(0, kPx) = H(1, kPy) = 1.0;
  const PoseVelocityCov& P = p.initial_cov;
  const Eigen::Matrix<double, 5, 2> K = P * H.transpose() * (H * P * H.transpose() + R).inverse();
  const PoseVelocity x = p.initial_state + K * (Eigen::Vector2d(0.7, 0.1) - H * p.initial_state);
  const PoseVelocityCov P1 = (PoseVelocityCov::Identity() - K * H) * P;
  EXPECT_LT((f.state() - x).norm(), 1e-12);
  EXPECT_LT((f.cov() - P1).norm(), 1e-12);
  EXPECT_TRUE(f.healthy());
}

// Odometry 10 % too fast along a straight line, and trusted; 1 Hz fixes of
// the truth keep the fused position near it (a lag behind each fix remains),
// where dead reckoning alone is 6 m ahead after 60 s.
TEST(PoseVelocityUkf, FixesPullADriftingPoseBack) {
  PoseUkfParams p;
  p.initial_cov = PoseVelocityCov::Identity() * 1e-4;
  PoseVelocityUkf f(p);
  const double dt = 0.1;
  for (int k = 1; k <= 600; ++k) {
    f.predict(dt);
    f.update_velocity(1.1, 0.0, Eigen::Vector2d(1e-4, 1e-4).asDiagonal());
    if (k % 10 == 0) f.update_position(k * dt, 0.0, Eigen::Matrix2d::Identity() * 0.01);
  }
  ASSERT_TRUE(f.healthy());
  EXPECT_LT(std::abs(f.state()(kPx) - 60.0), 0.25 * 6.0);
  EXPECT_NEAR(f.state()(kPy), 0.0, 0.05);
}

TEST(PoseVelocityUkf, BadParametersAndInputs) {
  PoseUkfParams p;
  std::string why;
  p.alpha = 0.0;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("alpha"), std::string::npos) << why;
  EXPECT_THROW(PoseVelocityUkf{p}, std::invalid_argument);
  p = {};
  p.initial_cov(0, 0) = -1.0;
  EXPECT_FALSE(p.IsValid(&why));
  p = {};
  PoseVelocityUkf f(p);
  f.update_position(std::numeric_limits<double>::quiet_NaN(), 0.0, Eigen::Matrix2d::Identity());
  EXPECT_FALSE(f.healthy());
  PoseVelocityUkf g(p);
  g.predict(-1.0);
  EXPECT_FALSE(g.healthy());
}

}  // namespace
}  // namespace odotune::filters

// Velocity UKF (odotune/filters/velocity_ukf.h): equals a linear Kalman filter written
// independently here (both models are linear, so the unscented transform is
// exact) on random sequences, parameter checks naming the bad value, health
// on non-finite input, the eq. 3 pose integration on a circle and NEES.
#include <gtest/gtest.h>

#include <Eigen/LU>  // inverse()
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include <odotune/filters/velocity_ukf.h>

namespace odotune::filters {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The textbook linear Kalman filter of the same model (random walk on (V, W),
// direct measurements), Joseph-form covariance update.
struct LinearKf {
  Eigen::Vector2d x;
  Eigen::Matrix2d P;
  Eigen::Vector2d q;  // rates [(m/s)²/s, (rad/s)²/s]

  void predict(double dt) { P += Eigen::Matrix2d(q.asDiagonal()) * dt; }
  template <int M>
  void update(const Eigen::Matrix<double, M, 2>& H, const Eigen::Matrix<double, M, 1>& z,
              const Eigen::Matrix<double, M, M>& R) {
    const Eigen::Matrix<double, M, M> S = H * P * H.transpose() + R;
    const Eigen::Matrix<double, 2, M> K = P * H.transpose() * S.inverse();
    x += K * (z - H * x);
    const Eigen::Matrix2d I_KH = Eigen::Matrix2d::Identity() - K * H;
    P = I_KH * P * I_KH.transpose() + K * R * K.transpose();
  }
};

void expect_close(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double rel, const char* what, int step) {
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    const double tol = rel * std::max(1.0, std::abs(b(i)));
    ASSERT_NEAR(a(i), b(i), tol) << what << " element " << i << " at step " << step;
  }
}

// Rounding: the sigma points x ± √((n+λ)P) carry the state's absolute
// rounding ε·|x| into deviations of size σ = √P, so the two filters agree to
// about ε·|x|/σ relative. The measurement σ here (≥ 5 mm/s, ≥ 3 mrad/s for the
// gyro) and states of order 1 keep that below 1e-12, the tolerance.
TEST(VelocityUkf, EqualsLinearKalmanFilterOnRandomSequences) {
  std::mt19937_64 rng(20230961);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto uniform = [&](double a, double b) { return a + (b - a) * u01(rng); };
  for (int trial = 0; trial < 50; ++trial) {
    UkfParams p;
    p.q_v_m2_s3 = std::pow(10.0, uniform(-4.0, 0.0));
    p.q_w_rad2_s3 = std::pow(10.0, uniform(-4.0, 0.0));
    p.alpha = uniform(0.5, 1.0);
    p.beta = uniform(0.0, 3.0);
    p.kappa = uniform(-1.0, 2.0);
    p.initial_state = Velocity(uniform(-1.0, 1.0), uniform(-1.0, 1.0));
    const double c = uniform(-0.5, 0.5) * 1e-2;
    p.initial_cov << 2e-2, c, c, 1e-2;
    VelocityUkf ukf(p);
    LinearKf kf{p.initial_state, p.initial_cov, Velocity(p.q_v_m2_s3, p.q_w_rad2_s3)};
    VelocityUkf free_ukf(p);
    LinearKf free_kf = kf;

    for (int step = 0; step < 200; ++step) {
      const double dt = uniform(0.0, 0.2);
      ukf.predict(dt);
      kf.predict(dt);
      // A full (V, W) measurement with a random SPD covariance.
      const Velocity z(uniform(-1.5, 1.5), uniform(-2.0, 2.0));
      const double sv = std::pow(10.0, uniform(-2.3, -1.0)), sw = std::pow(10.0, uniform(-2.3, -1.0));
      const double rho = uniform(-0.8, 0.8);
      VelocityCov R;
      R << sv * sv, rho * sv * sw, rho * sv * sw, sw * sw;
      ukf.update(z, R);
      kf.update<2>(Eigen::Matrix2d::Identity(), z, R);
      if (step % 3 == 0) {
        const double g = uniform(-2.0, 2.0), var = std::pow(10.0, uniform(-5.0, -2.0));
        ukf.update_yaw_rate(g, var);
        kf.update<1>(Eigen::Matrix<double, 1, 2>(0.0, 1.0), Eigen::Matrix<double, 1, 1>(g),
                     Eigen::Matrix<double, 1, 1>(var));
      }
      ASSERT_TRUE(ukf.healthy());
      // Per step (both from the same prior) the two agree to rounding; the
      // Kalman filter restarts from the UKF's posterior so that rounding
      // does not accumulate over the sequence (that is checked separately
      // below, with the free-running pair).
      expect_close(ukf.state(), kf.x, 1e-12, "state", step);
      expect_close(ukf.cov(), kf.P, 1e-12, "covariance", step);
      kf.x = ukf.state();
      kf.P = ukf.cov();
      free_ukf.predict(dt);
      free_kf.predict(dt);
      free_ukf.update(z, R);
      free_kf.update<2>(Eigen::Matrix2d::Identity(), z, R);
    }
    // Free-running over 200 steps: rounding stays at rounding level.
    expect_close(free_ukf.state(), free_kf.x, 1e-9, "free-running state", 200);
    expect_close(free_ukf.cov(), free_kf.P, 1e-9, "free-running covariance", 200);
  }
}

TEST(VelocityUkf, PredictAddsProcessNoiseRateTimesDt) {
  UkfParams p;
  p.q_v_m2_s3 = 0.3;
  p.q_w_rad2_s3 = 0.7;
  p.initial_state = Velocity(0.4, -0.2);
  p.initial_cov << 0.02, 0.005, 0.005, 0.01;
  VelocityUkf ukf(p);
  ukf.predict(0.25);
  EXPECT_NEAR(ukf.state()(kV), 0.4, 1e-15);
  EXPECT_NEAR(ukf.state()(kW), -0.2, 1e-15);
  EXPECT_NEAR(ukf.cov()(kV, kV), 0.02 + 0.3 * 0.25, 1e-15);
  EXPECT_NEAR(ukf.cov()(kW, kW), 0.01 + 0.7 * 0.25, 1e-15);
  EXPECT_NEAR(ukf.cov()(kV, kW), 0.005, 1e-15);
}

TEST(VelocityUkf, YawRateUpdateMovesVOnlyThroughCorrelation) {
  UkfParams p;
  p.initial_cov = VelocityCov::Identity() * 1e-2;
  VelocityUkf uncorrelated(p);
  uncorrelated.update_yaw_rate(1.0, 1e-2);
  EXPECT_EQ(uncorrelated.state()(kV), 0.0);
  EXPECT_NEAR(uncorrelated.state()(kW), 0.5, 1e-14);  // equal variances: halfway
  EXPECT_NEAR(uncorrelated.cov()(kW, kW), 0.5e-2, 1e-16);
  EXPECT_NEAR(uncorrelated.cov()(kV, kV), 1e-2, 1e-16);

  p.initial_cov << 1e-2, 0.5e-2, 0.5e-2, 1e-2;
  VelocityUkf correlated(p);
  correlated.update_yaw_rate(1.0, 1e-2);
  EXPECT_GT(correlated.state()(kV), 0.1);  // positive correlation pulls V up too
}

std::string invalid_message(const UkfParams& p) {
  std::string why;
  EXPECT_FALSE(p.IsValid(&why));
  return why;
}

TEST(VelocityUkf, ParamsValidationNamesTheBadValue) {
  std::string why;
  EXPECT_TRUE(UkfParams{}.IsValid(&why)) << why;

  auto with = [](auto&& edit) {
    UkfParams p;
    edit(p);
    return p;
  };
  EXPECT_NE(invalid_message(with([](UkfParams& p) { p.q_v_m2_s3 = -1.0; })).find("q_v_m2_s3 = -1"),
            std::string::npos);
  EXPECT_NE(invalid_message(with([](UkfParams& p) { p.q_w_rad2_s3 = kNaN; })).find("q_w_rad2_s3"),
            std::string::npos);
  EXPECT_NE(invalid_message(with([](UkfParams& p) { p.alpha = 0.0; })).find("alpha = 0"), std::string::npos);
  EXPECT_NE(invalid_message(with([](UkfParams& p) { p.alpha = 1.5; })).find("alpha = 1.5"), std::string::npos);
  EXPECT_NE(invalid_message(with([](UkfParams& p) { p.beta = -2.0; })).find("beta = -2"), std::string::npos);
  EXPECT_NE(invalid_message(with([](UkfParams& p) { p.kappa = -2.0; })).find("kappa = -2"), std::string::npos);
  EXPECT_NE(invalid_message(with([](UkfParams& p) { p.initial_state(kW) = kNaN; })).find("initial_state"),
            std::string::npos);
  EXPECT_NE(invalid_message(with([](UkfParams& p) { p.initial_cov(kV, kV) = -1.0; })).find("initial_cov"),
            std::string::npos);
  EXPECT_NE(invalid_message(with([](UkfParams& p) { p.initial_cov(kV, kW) = 0.5; })).find("initial_cov"),
            std::string::npos);  // not symmetric

  UkfParams bad;
  bad.alpha = -0.1;
  try {
    VelocityUkf ukf(bad);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("UkfParams: alpha"), std::string::npos) << e.what();
  }
}

TEST(VelocityUkf, UnhealthyOnNonFiniteInputAndSticks) {
  {
    VelocityUkf ukf(UkfParams{});
    EXPECT_TRUE(ukf.healthy());
    ukf.update(Velocity(kNaN, 0.0), VelocityCov::Identity());
    EXPECT_FALSE(ukf.healthy());
    ukf.predict(0.1);
    ukf.update(Velocity(0.0, 0.0), VelocityCov::Identity());
    EXPECT_FALSE(ukf.healthy());  // sticks
  }
  {
    VelocityUkf ukf(UkfParams{});
    ukf.predict(kNaN);
    EXPECT_FALSE(ukf.healthy());
  }
  {
    VelocityUkf ukf(UkfParams{});
    ukf.update_yaw_rate(0.1, std::numeric_limits<double>::infinity());
    EXPECT_FALSE(ukf.healthy());
  }
  {
    VelocityUkf ukf(UkfParams{});
    VelocityCov R;
    R << 1.0, 2.0, 2.0, 1.0;  // indefinite
    ukf.update(Velocity(0.0, 0.0), R);
    EXPECT_FALSE(ukf.healthy());
  }
  {
    VelocityUkf ukf(UkfParams{});
    ukf.update_yaw_rate(0.1, 0.0);  // zero variance
    EXPECT_FALSE(ukf.healthy());
  }
}

TEST(IntegratePose, ClosesARegularPolygonOnACircle) {
  // Eq. 3 turns the heading AFTER moving: with W·Δt = 2π/N the positions are
  // the vertices of a regular N-gon of side V·Δt, circumradius
  // V·Δt / (2 sin(π/N)), and the pose returns to the start after N steps.
  const int n = 64;
  const double v = 0.8, dt = 0.1;
  const double w = 2.0 * kPi / (n * dt);
  const double circumradius = v * dt / (2.0 * std::sin(kPi / n));
  const PlanarPose start{1.0, -2.0, 0.3};
  // The centre lies left of the first side's midpoint.
  const double half_side = 0.5 * v * dt;
  const double apothem = circumradius * std::cos(kPi / n);
  const double cx = start.x_m + half_side * std::cos(0.3) - apothem * std::sin(0.3);
  const double cy = start.y_m + half_side * std::sin(0.3) + apothem * std::cos(0.3);
  PlanarPose p = start;
  for (int k = 0; k < n; ++k) {
    p = integrate_pose(p, v, w, dt);
    EXPECT_NEAR(std::hypot(p.x_m - cx, p.y_m - cy), circumradius, 1e-12) << "step " << k;
  }
  EXPECT_NEAR(p.x_m, start.x_m, 1e-12);
  EXPECT_NEAR(p.y_m, start.y_m, 1e-12);
  EXPECT_NEAR(p.theta_rad, start.theta_rad + 2.0 * kPi, 1e-12);

  // First step by hand: along the initial heading.
  const PlanarPose q = integrate_pose(start, 2.0, 0.5, 0.1);
  EXPECT_DOUBLE_EQ(q.x_m, 1.0 + 0.2 * std::cos(0.3));
  EXPECT_DOUBLE_EQ(q.y_m, -2.0 + 0.2 * std::sin(0.3));
  EXPECT_DOUBLE_EQ(q.theta_rad, 0.35);
}

TEST(Nees, QuadraticFormOfTheInverseCovariance) {
  VelocityCov P;
  P << 4.0, 0.0, 0.0, 1.0;
  EXPECT_NEAR(nees(Velocity(1.0, 0.0), Velocity(0.0, 0.0), P), 0.25, 1e-15);
  EXPECT_NEAR(nees(Velocity(1.0, 2.0), Velocity(1.0, 0.0), P), 4.0, 1e-15);
  P << 2.0, 1.0, 1.0, 2.0;  // P⁻¹ = [2 −1; −1 2]/3
  EXPECT_NEAR(nees(Velocity(1.0, 1.0), Velocity(0.0, 0.0), P), 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(nees(Velocity(1.0, -1.0), Velocity(0.0, 0.0), P), 2.0, 1e-15);
  P << 1.0, 2.0, 2.0, 1.0;
  EXPECT_TRUE(std::isnan(nees(Velocity(1.0, 1.0), Velocity(0.0, 0.0), P)));
}

}  // namespace
}  // namespace odotune::filters

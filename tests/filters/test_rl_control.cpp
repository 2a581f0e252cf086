// robot_localization's control term (odotune/filters/rl_control.h) and the EKF's
// prediction with it: computeControlAcceleration's cases worked by hand, the
// two timeout rules, and ekf.cpp's order (the term applied after the
// transition and its Jacobian are taken from the state before it).
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/filters/rl_control.h>
#include <odotune/filters/rl_ekf.h>
#include <odotune/filters/rl_filter.h>

namespace rl = odotune::filters::rl;

namespace {

// The defaults of robot_localization's example files: vx and vyaw
// controlled, limits 1.3 m/s² and 3.4 rad/s² (4.5 decelerating), gains 0.8 / 0.9.
rl::RlControlParams control_example() {
  rl::RlControlParams p;
  p.update = {true, false, false, false, false, true};
  p.timeout_ns = 200'000'000;
  p.acceleration_limits = {1.3, 0.0, 0.0, 0.0, 0.0, 3.4};
  p.deceleration_limits = {1.3, 0.0, 0.0, 0.0, 0.0, 4.5};
  p.acceleration_gains = {0.8, 0.0, 0.0, 0.0, 0.0, 0.9};
  p.deceleration_gains = {1.0, 0.0, 0.0, 0.0, 0.0, 1.0};
  return p;
}

rl::RlEkfParams control_filter(const rl::State& x0) {
  rl::RlEkfParams p;
  p.process_noise = rl::Cov::Identity() * 0.01;
  p.initial_state = x0;
  p.control = control_example();
  return p;
}

}  // namespace

TEST(RlControl, AccelerationFollowsTheCommandWithinItsLimit) {
  // From rest toward 1 m/s: error 1, gain 0.8 → 0.8 (below the 1.3 limit).
  EXPECT_DOUBLE_EQ(rl::control_acceleration(0.0, 1.0, 1.3, 0.8, 1.3, 1.0), 0.8);
  // Toward 5 m/s: 0.8 · 5 = 4 is clamped to 1.3.
  EXPECT_DOUBLE_EQ(rl::control_acceleration(0.0, 5.0, 1.3, 0.8, 1.3, 1.0), 1.3);
  // Backwards from rest: −0.8.
  EXPECT_DOUBLE_EQ(rl::control_acceleration(0.0, -1.0, 1.3, 0.8, 1.3, 1.0), -0.8);
}

TEST(RlControl, SlowingDownUsesTheDecelerationLimitAndGain) {
  // At 2 m/s toward 1 m/s: the set point 1 is below |v|, so decelerating:
  // gain 1.0 · (1 − 2) = −1, within the deceleration limit 4.5.
  EXPECT_DOUBLE_EQ(rl::control_acceleration(2.0, 1.0, 3.4, 0.9, 4.5, 1.0), -1.0);
  // At 2 m/s under a command of −1 m/s: |e| = 3 > |u| + 0.01, so the set
  // point is 0 and the robot decelerates, gain 1.0 · (−3) = −3 (limit 4.5);
  // with limit 2, clamped.
  EXPECT_DOUBLE_EQ(rl::control_acceleration(2.0, -1.0, 3.4, 0.9, 4.5, 1.0), -3.0);
  EXPECT_DOUBLE_EQ(rl::control_acceleration(2.0, -1.0, 3.4, 0.9, 2.0, 1.0), -2.0);
}

TEST(RlControl, TimeoutRulesOfRos1AndRos2) {
  rl::RlControlParams p = control_example();
  rl::Command c;
  c.u = {1.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  c.time_ns = 10'000'000'000;
  const rl::ControlVector v{};
  // 0.1 s after the command: within the 0.2 s timeout under both rules.
  EXPECT_DOUBLE_EQ(rl::control_accelerations(p, c, v, 10'100'000'000)[rl::kCVx], 0.8);
  // 0.2 s after it: timed out (≥), the command taken as 0, from rest 0.
  EXPECT_DOUBLE_EQ(rl::control_accelerations(p, c, v, 10'200'000'000)[rl::kCVx], 0.0);
  // 0.3 s before it (a measurement older than the command): ROS 1 compares
  // |t − t_u|, timed out; ROS 2 compares t − t_u, not.
  EXPECT_DOUBLE_EQ(rl::control_accelerations(p, c, v, 9'700'000'000)[rl::kCVx], 0.0);
  p.timeout_rule = rl::ControlTimeout::forward;
  EXPECT_DOUBLE_EQ(rl::control_accelerations(p, c, v, 9'700'000'000)[rl::kCVx], 0.8);
  // A member that is not controlled gets nothing.
  c.u[rl::kCVy] = 1.0;
  EXPECT_DOUBLE_EQ(rl::control_accelerations(p, c, v, 10'100'000'000)[rl::kCVy], 0.0);
}

TEST(RlControl, ParametersAreChecked) {
  rl::RlControlParams p = control_example();
  std::string why;
  EXPECT_TRUE(p.IsValid(&why));
  p.deceleration_gains[5] = -1.0;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("deceleration_gains[5]"), std::string::npos) << why;
  p = control_example();
  p.timeout_ns = -1;
  EXPECT_FALSE(p.IsValid(&why));
  rl::RlEkfParams f = control_filter(rl::State::Zero());
  f.control->acceleration_limits[0] = std::nan("");
  EXPECT_THROW(rl::RlEkf bad(f), std::invalid_argument) << "an invalid control term must not construct";
}

// ekf.cpp's predict: a_x set to the control's acceleration, the yaw rate
// raised by a·Δt, then x = A·x. From rest under (1 m/s, 1 rad/s) for 0.1 s:
// a_x = 0.8, v_x = 0.08, x = 0.004; ω = 0.09, yaw = 0.009.
TEST(RlEkfControl, PredictionAppliesTheCommandFirst) {
  rl::RlEkf f(control_filter(rl::State::Zero()));
  f.set_command({{1.0, 0.0, 0.0, 0.0, 0.0, 1.0}, 0});
  f.predict(0.1);
  EXPECT_NEAR(f.state()[rl::kAx], 0.8, 1e-15);
  EXPECT_NEAR(f.state()[rl::kVx], 0.08, 1e-15);
  EXPECT_NEAR(f.state()[rl::kX], 0.004, 1e-15);
  EXPECT_NEAR(f.state()[rl::kVyaw], 0.09, 1e-15);
  EXPECT_NEAR(f.state()[rl::kYaw], 0.009, 1e-15);
}

// A command older than the timeout is taken as 0: a robot moving at 1 m/s
// brakes at the deceleration gain, −1 m/s², from the measurement's time on.
TEST(RlEkfControl, TimedOutCommandBrakes) {
  rl::State x0 = rl::State::Zero();
  x0[rl::kVx] = 1.0;
  rl::RlEkf f(control_filter(x0));
  f.set_command({{1.0, 0.0, 0.0, 0.0, 0.0, 0.0}, 0});
  rl::Measurement m;  // initialises nothing (no member fused) at t = 1 s
  m.time_ns = 1'000'000'000;
  f.process(m);
  f.predict_to(1'100'000'000);  // 1.1 s after the command: timed out
  EXPECT_NEAR(f.state()[rl::kAx], -1.0, 1e-15);
  EXPECT_NEAR(f.state()[rl::kVx], 0.9, 1e-15);
  EXPECT_NEAR(f.state()[rl::kX], 0.1 - 0.005, 1e-15);
}

// The covariance is projected with the Jacobian of the state before the
// control term: the same as a filter without control whose state is that one.
TEST(RlEkfControl, CovarianceProjectedFromTheStateBeforeTheTerm) {
  rl::State x0 = rl::State::Zero();
  x0[rl::kYaw] = 0.3;
  x0[rl::kVx] = 0.5;
  x0[rl::kAx] = 0.2;
  rl::RlEkfParams with = control_filter(x0), without = with;
  without.control.reset();
  with.initial_cov = without.initial_cov = rl::Cov::Identity() * 0.1;
  rl::RlEkf a(with), b(without);
  a.set_command({{1.0, 0.0, 0.0, 0.0, 0.0, 0.0}, 0});
  a.predict(0.1);
  b.predict(0.1);
  EXPECT_TRUE(a.cov().isApprox(b.cov(), 1e-15)) << "P must not depend on the command";
  EXPECT_GT(std::abs(a.state()[rl::kVx] - b.state()[rl::kVx]), 0.01);
}

// ukf_node computes the term but its projection does not use it.
TEST(RlUkfControl, CommandChangesNothing) {
  rl::RlEkfParams p = control_filter(rl::State::Zero());
  rl::RlFilter with(rl::RlFilterType::ukf, p);
  p.control.reset();
  rl::RlFilter without(rl::RlFilterType::ukf, p);
  with.set_command({{1.0, 0.0, 0.0, 0.0, 0.0, 1.0}, 0});
  with.predict(0.1);
  without.predict(0.1);
  EXPECT_EQ(with.state(), without.state());
}

TEST(RlEkfControl, LanesRefuseTheControlTerm) {
  const std::vector<rl::RlEkfParams> p{control_filter(rl::State::Zero())};
  EXPECT_THROW(rl::RlEkfLanes lanes(p), std::invalid_argument);
}

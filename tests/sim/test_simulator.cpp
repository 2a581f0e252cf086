// The simulator (odotune/sim/simulator.h) and the motion profile: each physics
// effect changes exactly what physics-effects.md says and nothing else; the
// nominal kinematics of track-format.md reproduce the ground truth from the
// ticks; noise is seeded and has the configured size; commands respect the
// acceleration limits.
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/sim/effects.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/simulator.h>
#include <odotune/tracks/track_io.h>

namespace odotune::sim {
namespace {

using ::testing::HasSubstr;

Segment straight(double d, double v) {
  Segment s;
  s.kind = Segment::Kind::straight;
  s.distance_m = d;
  s.speed_m_s = v;
  return s;
}
Segment arc(double r, double deg, double v) {
  Segment s;
  s.kind = Segment::Kind::arc;
  s.radius_m = r;
  s.angle_deg = deg;
  s.speed_m_s = v;
  return s;
}
Segment spin(double deg, double rate) {
  Segment s;
  s.kind = Segment::Kind::spin;
  s.angle_deg = deg;
  s.rate_deg_s = rate;
  return s;
}
Segment stop(double dur) {
  Segment s;
  s.kind = Segment::Kind::stop;
  s.duration_s = dur;
  return s;
}

// All sensors at 100 Hz, no noise and full precision: the columns show the
// true values, so effects can be checked number by number.
Scenario quiet(std::vector<Segment> segs) {
  Scenario sc;
  sc.seed = 42;
  sc.motion.segments = std::move(segs);
  auto& s = sc.sensors;
  s.encoders.omega = true;
  s.encoders.omega_resolution_rad_s = 0;
  s.commands.resolution = 0;
  s.gyro.sigma_rad_s = 0;
  s.gyro.resolution_rad_s = 0;
  s.power.sigma_w = 0;
  s.power.resolution_w = 0;
  s.ext_velocity.rate_hz = 100;
  s.ext_velocity.sigma_v_m_s = 0;
  s.ext_velocity.sigma_w_rad_s = 0;
  s.ext_velocity.resolution = 0;
  s.aps.resolution_m = 0;
  s.ground_truth.resolution_m = 0;
  s.ground_truth.resolution_rad = 0;
  return sc;
}

std::string text_of(const tracks::Track& t) {
  std::ostringstream out;
  tracks::format_track(t, out);
  return out.str();
}

// Row index of time t (rows at 100 Hz in the quiet scenarios).
std::size_t row_at_time(const tracks::Track& tr, double t) {
  std::size_t i = 0;
  while (i + 1 < tr.size() && tr.t()[i] < t - 1e-9) ++i;
  return i;
}

double tick_m(const tracks::Track& tr) {
  return 2 * std::numbers::pi * *tr.meta().wheel_radius_left_m / *tr.meta().ticks_per_rev;
}

// Ground distance along gt and mean-wheel distance from the ticks between rows a and b.
double gt_distance(const tracks::Track& tr, std::size_t a, std::size_t b) {
  double d = 0;
  for (std::size_t i = a; i < b; ++i)
    d += std::hypot(tr.col(tracks::Col::gt_x)[i + 1] - tr.col(tracks::Col::gt_x)[i],
                    tr.col(tracks::Col::gt_y)[i + 1] - tr.col(tracks::Col::gt_y)[i]);
  return d;
}
double tick_distance(const tracks::Track& tr, std::size_t a, std::size_t b) {
  const double dl = static_cast<double>(tr.ticks_l()[b] - tr.ticks_l()[a]);
  const double dr = static_cast<double>(tr.ticks_r()[b] - tr.ticks_r()[a]);
  return 0.5 * (dl + dr) * tick_m(tr);
}

TEST(Simulator, NominalKinematicsReproduceGroundTruthFromTicks) {
  Scenario sc = quiet({stop(1), straight(3, 0.6), arc(0.8, 120, 0.4), spin(-200, 90), arc(1.5, -90, 0.5),
                       straight(-1, 0.3), arc(0.4, 360, 0.3), stop(1)});
  const tracks::Track tr = simulate(sc);
  ASSERT_TRUE(tr.has_ticks());
  const double D = 0.30, q = tick_m(tr);
  // track-format.md kinematics, exact arc per row step.
  double x = 0, y = 0, th = 0, path = 0, max_th = 0, max_pos = 0;
  for (std::size_t i = 1; i < tr.size(); ++i) {
    const double sl = static_cast<double>(tr.ticks_l()[i] - tr.ticks_l()[i - 1]) * q;
    const double sr = static_cast<double>(tr.ticks_r()[i] - tr.ticks_r()[i - 1]) * q;
    const double ds = 0.5 * (sl + sr), dth = (sr - sl) / D;
    const double half = 0.5 * dth, sinc = std::abs(half) < 1e-9 ? 1.0 : std::sin(half) / half;
    x += ds * sinc * std::cos(th + half);
    y += ds * sinc * std::sin(th + half);
    th += dth;
    path += std::abs(ds);
    max_th = std::max(max_th, std::abs(th - tr.col(tracks::Col::gt_theta)[i]));
    max_pos = std::max(max_pos, std::hypot(x - tr.col(tracks::Col::gt_x)[i], y - tr.col(tracks::Col::gt_y)[i]));
  }
  // Heading from cumulative ticks is off by at most one count per wheel.
  const double th_bound = 2 * q / D + 1e-9;
  EXPECT_LT(max_th, th_bound);
  // Position: heading bound over the path plus one count of each wheel.
  EXPECT_LT(max_pos, path * th_bound + 2 * q);
  EXPECT_GT(path, 8.0);
  EXPECT_LT(max_pos, 5e-3);
}

TEST(Simulator, RadiusErrorCurvesTheTruePathButNotTheTicks) {
  Scenario nominal = quiet({straight(4, 0.5), stop(0.5)});
  Scenario bigger = nominal;
  bigger.effects.radius_error = Effects::RadiusError{1.0, 1.01};
  const tracks::Track a = simulate(nominal), b = simulate(bigger);
  EXPECT_EQ(a.ticks_l(), b.ticks_l());
  EXPECT_EQ(a.ticks_r(), b.ticks_r());
  const std::size_t n = a.size() - 1;
  EXPECT_NEAR(a.col(tracks::Col::gt_theta)[n], 0.0, 1e-12);
  EXPECT_NEAR(a.col(tracks::Col::gt_y)[n], 0.0, 1e-12);
  // True heading change = (R_r_true*phi_r - R_l*phi_l)/D, phi from the ticks (+-1 count).
  const double q = tick_m(b);
  const double expect = (1.01 * static_cast<double>(b.ticks_r()[n]) - static_cast<double>(b.ticks_l()[n])) * q /
                        0.30;
  EXPECT_NEAR(b.col(tracks::Col::gt_theta)[n], expect, 2 * q / 0.30);
  EXPECT_GT(expect, 0.1);
  EXPECT_GT(b.col(tracks::Col::gt_y)[n], 0.1);  // curves left
}

TEST(Simulator, WheelBaseErrorScalesTheTurnRate) {
  Scenario nominal = quiet({spin(360, 90), stop(0.5)});
  Scenario wide = nominal;
  wide.effects.wheel_base_error = Effects::WheelBaseError{1.1};
  const tracks::Track a = simulate(nominal), b = simulate(wide);
  EXPECT_EQ(a.ticks_l(), b.ticks_l());
  const std::size_t n = a.size() - 1;
  EXPECT_NEAR(a.col(tracks::Col::gt_theta)[n], 2 * std::numbers::pi, 1e-5);
  EXPECT_NEAR(b.col(tracks::Col::gt_theta)[n], 2 * std::numbers::pi / 1.1, 1e-5);
  const std::size_t mid = row_at_time(a, 2.0);  // cruise of the spin
  EXPECT_NEAR(b.col(tracks::Col::gyro_z)[mid], a.col(tracks::Col::gyro_z)[mid] / 1.1, 1e-12);
}

TEST(Simulator, RadiusStepActsFromItsTimeOn) {
  Scenario sc = quiet({straight(8, 0.5)});
  sc.effects.radius_step = Effects::RadiusStep{6.0, 1.02, 1.02};
  const tracks::Track tr = simulate(sc);
  const auto ratio = [&](double t0, double t1) {
    const std::size_t a = row_at_time(tr, t0), b = row_at_time(tr, t1);
    return gt_distance(tr, a, b) / tick_distance(tr, a, b);
  };
  EXPECT_NEAR(ratio(2.0, 5.9), 1.0, 1e-3);
  EXPECT_NEAR(ratio(6.1, 10.0), 1.02, 1e-3);
}

TEST(Simulator, SpeedRadiusGrowsWithSpeed) {
  const auto ratio_at = [](double v) {
    Scenario sc = quiet({straight(6 * v, v)});
    sc.effects.speed_radius = Effects::SpeedRadius{0.05};
    const tracks::Track tr = simulate(sc);
    const std::size_t a = row_at_time(tr, 2.5), b = row_at_time(tr, 5.0);  // cruise
    return gt_distance(tr, a, b) / tick_distance(tr, a, b);
  };
  // R_eff = R(1 + c u^2), u = R*omega = v (nominal radii).
  EXPECT_NEAR(ratio_at(0.2) - 1, 0.05 * 0.04, 1e-4);
  EXPECT_NEAR(ratio_at(1.0) - 1, 0.05 * 1.0, 1e-3);
}

TEST(Simulator, LateralSkidGivesMinusKVW) {
  const auto lateral = [](double k) {
    Scenario sc = quiet({arc(1.0, 180, 0.5)});
    if (k > 0) sc.effects.lateral_skid = Effects::LateralSkid{k};
    const tracks::Track tr = simulate(sc);
    const std::size_t a = row_at_time(tr, 3.0), b = row_at_time(tr, 4.0);
    double sum = 0;
    for (std::size_t i = a; i < b; ++i) {
      const double thm = 0.5 * (tr.col(tracks::Col::gt_theta)[i] + tr.col(tracks::Col::gt_theta)[i + 1]);
      const double dx = tr.col(tracks::Col::gt_x)[i + 1] - tr.col(tracks::Col::gt_x)[i];
      const double dy = tr.col(tracks::Col::gt_y)[i + 1] - tr.col(tracks::Col::gt_y)[i];
      sum += (-std::sin(thm) * dx + std::cos(thm) * dy) / (tr.t()[i + 1] - tr.t()[i]);
    }
    return sum / static_cast<double>(b - a);
  };
  EXPECT_NEAR(lateral(0.0), 0.0, 1e-6);
  const double v = 0.5, w = 0.5;
  EXPECT_NEAR(lateral(0.05), -0.05 * v * w, 0.01 * 0.05 * v * w);
}

TEST(Simulator, LongitudinalSlipOnlyWhileAccelerating) {
  const auto run = [](double k) {
    Scenario sc = quiet({straight(3, 0.5)});
    sc.motion.max_accel_m_s2 = 0.5;  // 1 s ramp
    sc.effects.longitudinal_slip = Effects::LongitudinalSlip{k};
    return simulate(sc);
  };
  const tracks::Track tr = run(0.2);
  const auto ratio = [&](double t0, double t1) {
    const std::size_t a = row_at_time(tr, t0), b = row_at_time(tr, t1);
    return gt_distance(tr, a, b) / tick_distance(tr, a, b);
  };
  EXPECT_NEAR(ratio(0.2, 0.8), 1 - 0.2 * 0.5, 2e-3);  // s = k*|du/dt|
  EXPECT_NEAR(ratio(2.0, 5.0), 1.0, 1e-3);            // cruise
  EXPECT_NEAR(ratio(6.2, 6.8), 1 - 0.2 * 0.5, 2e-3);  // braking
  const tracks::Track capped = run(10.0);
  const std::size_t a = row_at_time(capped, 0.2), b = row_at_time(capped, 0.8);
  EXPECT_NEAR(gt_distance(capped, a, b) / tick_distance(capped, a, b), 0.5, 2e-3);  // s <= 0.5
}

TEST(Simulator, SlipZoneOnlyInsideTheBox) {
  Scenario sc = quiet({straight(5, 0.5)});
  sc.effects.slip_zone = Effects::SlipZone{2.0, 3.0, -1.0, 1.0, 0.2, 0.2};
  const tracks::Track tr = simulate(sc);
  std::size_t in0 = 0, in1 = 0, out0 = 0, out1 = 0;
  for (std::size_t i = 0; i < tr.size(); ++i) {
    const double x = tr.col(tracks::Col::gt_x)[i];
    if (!in0 && x > 2.05) in0 = i;
    if (!in1 && x > 2.95) in1 = i;
    if (!out0 && x > 0.5) out0 = i;
    if (!out1 && x > 1.9) out1 = i;
  }
  ASSERT_TRUE(in0 && in1 && out0 && out1);
  EXPECT_NEAR(gt_distance(tr, in0, in1) / tick_distance(tr, in0, in1), 0.8, 2e-3);
  EXPECT_NEAR(gt_distance(tr, out0, out1) / tick_distance(tr, out0, out1), 1.0, 1e-3);

  // One-sided slip turns the robot only while inside.
  sc.effects.slip_zone->s_l = 0.0;
  const tracks::Track one = simulate(sc);
  double th_before = 0, th_after = 0;
  for (std::size_t i = 0; i < one.size(); ++i) {
    if (one.col(tracks::Col::gt_x)[i] < 1.99)
      th_before = std::max(th_before, std::abs(one.col(tracks::Col::gt_theta)[i]));
  }
  EXPECT_EQ(th_before, 0.0);
  const std::size_t last = one.size() - 1;
  th_after = one.col(tracks::Col::gt_theta)[last];
  EXPECT_LT(th_after, -0.05);  // right wheel slips: turns right
  EXPECT_GT(one.col(tracks::Col::gt_x)[last], 3.5);
  std::size_t left_box = 0;
  for (std::size_t i = 0; i < one.size(); ++i)
    if (!left_box && one.col(tracks::Col::gt_x)[i] > 3.1) left_box = i;
  EXPECT_NEAR(one.col(tracks::Col::gt_theta)[left_box], th_after, 1e-12);  // no turning after the box
}

TEST(Simulator, GyroBiasShiftsTheGyroByB) {
  Scenario sc = quiet({stop(1), arc(1.0, 90, 0.5), stop(1)});
  sc.sensors.gyro.sigma_rad_s = 0.002;  // with noise: the same seed gives the same noise
  sc.sensors.gyro.resolution_rad_s = 1e-5;
  Scenario biased = sc;
  biased.effects.gyro_bias = Effects::GyroBias{0.01};
  const tracks::Track a = simulate(sc), b = simulate(biased);
  double mean = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = b.col(tracks::Col::gyro_z)[i] - a.col(tracks::Col::gyro_z)[i];
    EXPECT_NEAR(d, 0.01, 1.01e-5) << i;
    mean += d;
  }
  EXPECT_NEAR(mean / static_cast<double>(a.size()), 0.01, 1e-6);
  EXPECT_EQ(a.col(tracks::Col::gt_theta), b.col(tracks::Col::gt_theta));
}

TEST(Simulator, GyroScaleScalesTheGyro) {
  Scenario sc = quiet({arc(0.5, -270, 0.4), spin(90, 120)});
  sc.effects.gyro_scale = Effects::GyroScale{1.05};
  const tracks::Track tr = simulate(sc);
  double max_w = 0;
  for (std::size_t i = 0; i < tr.size(); ++i) {
    EXPECT_NEAR(tr.col(tracks::Col::gyro_z)[i], 1.05 * tr.col(tracks::Col::w_ext)[i], 1e-12);
    max_w = std::max(max_w, std::abs(tr.col(tracks::Col::w_ext)[i]));
  }
  EXPECT_GT(max_w, 0.7);
}

TEST(Simulator, ActuatorLagMakesTrueVelocityLagTheCommand) {
  const auto rise = [](double tau) {
    Scenario sc = quiet({straight(5, 0.5)});
    sc.motion.max_accel_m_s2 = 1000;  // a step, 0.5 ms ramp
    sc.sensors.ext_velocity.rate_hz = 1000;
    if (tau > 0) sc.effects.actuator_lag = Effects::ActuatorLag{tau};
    const tracks::Track tr = simulate(sc);
    for (std::size_t i = 0; i < tr.size(); ++i)
      if (tr.at(tracks::Col::v_ext, i) && tr.col(tracks::Col::v_ext)[i] >= (1 - std::exp(-1.0)) * 0.5)
        return tr.t()[i];
    return -1.0;
  };
  EXPECT_LE(rise(0.0), 0.002);
  EXPECT_NEAR(rise(0.2), 0.2, 0.003);  // 63 % rise time = tau
  EXPECT_NEAR(rise(0.05), 0.05, 0.003);
}

TEST(Simulator, TimeOffsetShiftsOnlyTheOdometryColumns) {
  Scenario sc = quiet({stop(0.2), straight(1, 0.5), arc(0.5, 90, 0.4), stop(0.2)});
  Scenario late = sc, early = sc;
  late.effects.time_offset = Effects::TimeOffset{0.05};    // 5 rows at 100 Hz
  early.effects.time_offset = Effects::TimeOffset{-0.03};  // 3 rows
  const tracks::Track a = simulate(sc), b = simulate(late), c = simulate(early);
  ASSERT_EQ(a.size(), b.size());
  const std::size_t n = a.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t from = i >= 5 ? i - 5 : 0;  // first value held before t = 0
    EXPECT_EQ(b.ticks_l()[i], a.ticks_l()[from]) << i;
    EXPECT_EQ(b.ticks_r()[i], a.ticks_r()[from]) << i;
    EXPECT_EQ(b.col(tracks::Col::v_cmd)[i], a.col(tracks::Col::v_cmd)[from]) << i;
    EXPECT_EQ(b.col(tracks::Col::w_cmd)[i], a.col(tracks::Col::w_cmd)[from]) << i;
    EXPECT_NEAR(b.col(tracks::Col::omega_r)[i], a.col(tracks::Col::omega_r)[from], 1e-12) << i;
    const std::size_t ahead = std::min(i + 3, n - 1);  // last value held after the end
    EXPECT_EQ(c.ticks_l()[i], a.ticks_l()[ahead]) << i;
  }
  EXPECT_EQ(a.col(tracks::Col::gt_x), b.col(tracks::Col::gt_x));
  EXPECT_EQ(a.col(tracks::Col::gyro_z), b.col(tracks::Col::gyro_z));
  EXPECT_EQ(a.col(tracks::Col::power_l), b.col(tracks::Col::power_l));
}

// Nominal dead reckoning (track-format.md kinematics, nominal radii and base)
// of the recorded ticks from row 0 to every row.
struct DeadReckoned {
  std::vector<double> x, y, th;
};
DeadReckoned dead_reckon_ticks(const tracks::Track& tr) {
  const double q = tick_m(tr), D = *tr.meta().wheel_base_m;
  DeadReckoned dr{{0.0}, {0.0}, {0.0}};
  for (std::size_t i = 1; i < tr.size(); ++i) {
    const double sl = static_cast<double>(tr.ticks_l()[i] - tr.ticks_l()[i - 1]) * q;
    const double sr = static_cast<double>(tr.ticks_r()[i] - tr.ticks_r()[i - 1]) * q;
    const double ds = 0.5 * (sl + sr), dth = (sr - sl) / D;
    const double half = 0.5 * dth, sinc = std::abs(half) < 1e-9 ? 1.0 : std::sin(half) / half;
    dr.x.push_back(dr.x.back() + ds * sinc * std::cos(dr.th.back() + half));
    dr.y.push_back(dr.y.back() + ds * sinc * std::sin(dr.th.back() + half));
    dr.th.push_back(dr.th.back() + dth);
  }
  return dr;
}

// physics-effects.md: "the odometry's body velocities read v + b_v and w +
// b_w ... so a robot standing still seems to move". The robot stands for 10 s.
TEST(Simulator, OdometryBiasBvMakesAStandingRobotsOdometryDriftByBvT) {
  Scenario sc = quiet({stop(10)});
  sc.effects.odometry_bias = Effects::OdometryBias{0.02, 0.0};
  const tracks::Track tr = simulate(sc);
  ASSERT_GT(tr.duration_s(), 9.99);
  const double q = tick_m(tr), R = 0.05;
  const DeadReckoned dr = dead_reckon_ticks(tr);
  for (std::size_t i = 0; i < tr.size(); ++i) {
    const double t = tr.t()[i];
    // The world stands still; the gyro and the other sensors see it.
    ASSERT_EQ(tr.col(tracks::Col::gt_x)[i], 0.0) << i;
    ASSERT_EQ(tr.col(tracks::Col::gt_y)[i], 0.0) << i;
    ASSERT_EQ(tr.col(tracks::Col::gt_theta)[i], 0.0) << i;
    ASSERT_EQ(tr.col(tracks::Col::gyro_z)[i], 0.0) << i;
    ASSERT_EQ(tr.col(tracks::Col::v_ext)[i], 0.0) << i;
    // The odometry moves: b_v*t, within one count per wheel, straight ahead.
    ASSERT_NEAR(dr.x[i], 0.02 * t, q + 1e-12) << i;
    ASSERT_NEAR(dr.y[i], 0.0, 1e-12) << i;
    ASSERT_NEAR(dr.th[i], 0.0, 2 * q / 0.30 + 1e-12) << i;
    ASSERT_NEAR(tr.col(tracks::Col::omega_l)[i], 0.02 / R, 1e-12) << i;
    ASSERT_NEAR(tr.col(tracks::Col::omega_r)[i], 0.02 / R, 1e-12) << i;
    ASSERT_EQ(tr.col(tracks::Col::v_cmd)[i], 0.02) << i;
    ASSERT_EQ(tr.col(tracks::Col::w_cmd)[i], 0.0) << i;
  }
  EXPECT_NEAR(dr.x.back(), 0.2, q);      // 20 cm in 10 s at rest
  EXPECT_GT(tr.ticks_l().back(), 2000);  // 0.2 m / (2 pi 0.05 m / 4096) = 2608 counts

  // While moving, too: the recorded ticks' nominal travel exceeds that of the
  // same run without the bias by b_v*t (one count per wheel and run).
  Scenario moving = quiet({stop(1), straight(2, 0.5), arc(0.8, 90, 0.4), stop(1)});
  Scenario biased = moving;
  biased.effects.odometry_bias = Effects::OdometryBias{-0.03, 0.0};
  const tracks::Track a = simulate(moving), b = simulate(biased);
  ASSERT_EQ(a.t(), b.t());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_NEAR(tick_distance(b, 0, i) - tick_distance(a, 0, i), -0.03 * a.t()[i], 2 * q) << i;
    ASSERT_NEAR(b.col(tracks::Col::v_cmd)[i] - a.col(tracks::Col::v_cmd)[i], -0.03, 1e-12) << i;
  }
  EXPECT_EQ(a.col(tracks::Col::gt_x), b.col(tracks::Col::gt_x));
  EXPECT_EQ(a.col(tracks::Col::gyro_z), b.col(tracks::Col::gyro_z));
  EXPECT_EQ(a.col(tracks::Col::power_l), b.col(tracks::Col::power_l));
}

TEST(Simulator, OdometryBiasBwMakesTheOdometrysHeadingDriftByBwT) {
  Scenario sc = quiet({stop(10)});
  sc.effects.odometry_bias = Effects::OdometryBias{0.0, 0.05};
  const tracks::Track tr = simulate(sc);
  const double q = tick_m(tr), R = 0.05, D = 0.30;
  const DeadReckoned dr = dead_reckon_ticks(tr);
  for (std::size_t i = 0; i < tr.size(); ++i) {
    const double t = tr.t()[i];
    ASSERT_EQ(tr.col(tracks::Col::gt_theta)[i], 0.0) << i;
    ASSERT_EQ(tr.col(tracks::Col::gyro_z)[i], 0.0) << i;
    ASSERT_EQ(tr.col(tracks::Col::w_ext)[i], 0.0) << i;
    // A spin on the spot in the odometry: heading b_w*t, no travel.
    ASSERT_NEAR(dr.th[i], 0.05 * t, 2 * q / D + 1e-12) << i;
    ASSERT_NEAR(std::hypot(dr.x[i], dr.y[i]), 0.0, q) << i;
    ASSERT_NEAR(tr.col(tracks::Col::omega_l)[i], -0.05 * D / 2 / R, 1e-12) << i;
    ASSERT_NEAR(tr.col(tracks::Col::omega_r)[i], 0.05 * D / 2 / R, 1e-12) << i;
    ASSERT_EQ(tr.col(tracks::Col::v_cmd)[i], 0.0) << i;
    ASSERT_EQ(tr.col(tracks::Col::w_cmd)[i], 0.05) << i;
  }
  EXPECT_NEAR(dr.th.back(), 0.5, 2 * q / D);

  // The offsets sit on the NOMINAL model's body velocities: with unequal
  // nominal radii and both offsets, the recorded wheel rates still read
  // exactly (v + b_v, w + b_w) through track-format.md's kinematics.
  Scenario odd = quiet({straight(1, 0.4), arc(0.5, -90, 0.3)});
  odd.robot.wheel_radius_left_m = 0.049;
  odd.robot.wheel_radius_right_m = 0.052;
  odd.robot.wheel_base_m = 0.33;
  odd.effects.radius_error = Effects::RadiusError{0.99, 1.02};  // the world differs; the offset does not
  Scenario odd_biased = odd;
  odd_biased.effects.odometry_bias = Effects::OdometryBias{0.01, -0.04};
  const tracks::Track a = simulate(odd), b = simulate(odd_biased);
  auto body = [](const tracks::Track& t, std::size_t i) {
    const double ul = t.col(tracks::Col::omega_l)[i] * 0.049, ur = t.col(tracks::Col::omega_r)[i] * 0.052;
    return std::pair<double, double>{0.5 * (ur + ul), (ur - ul) / 0.33};
  };
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto [va, wa] = body(a, i);
    const auto [vb, wb] = body(b, i);
    ASSERT_NEAR(vb - va, 0.01, 1e-12) << i;
    ASSERT_NEAR(wb - wa, -0.04, 1e-12) << i;
  }
  EXPECT_EQ(a.col(tracks::Col::gt_theta), b.col(tracks::Col::gt_theta));
}

TEST(Simulator, OdometryBiasAtZeroIsANoOp) {
  // Switched on at its defaults (b_v = b_w = 0), every column keeps its bits;
  // only sim.effects names it. (Switched off, tracks keep the bytes they had
  // before the effect existed: ReferenceScenarios.RegenerateTheCommittedTracks
  // ByteForByte in tests/formats.)
  Scenario sc;  // default, noisy, quantised sensors
  sc.sensors.encoders.omega = true;
  sc.motion.segments = {stop(0.5), straight(-1, 0.4), arc(0.6, 120, 0.3), stop(0.5)};
  sc.effects.time_offset = Effects::TimeOffset{0.02};
  Scenario zero = sc;
  apply_effect(zero.effects, parse_effect_spec("odometry_bias"));
  ASSERT_TRUE(zero.effects.odometry_bias);
  EXPECT_EQ(zero.effects.odometry_bias->b_v, 0.0);
  EXPECT_EQ(zero.effects.odometry_bias->b_w, 0.0);
  const tracks::Track a = simulate(sc), b = simulate(zero);
  EXPECT_EQ(b.meta().get("sim.effects"), "time_offset:dt=0.02; odometry_bias:b_v=0,b_w=0");
  std::string ta = text_of(a), tb = text_of(b);
  const std::string from = "time_offset:dt=0.02\n", to = "time_offset:dt=0.02; odometry_bias:b_v=0,b_w=0\n";
  const auto at = ta.find(from);
  ASSERT_NE(at, std::string::npos);
  ta.replace(at, from.size(), to);
  EXPECT_TRUE(ta == tb) << "odometry_bias at 0 changed the track";
}

// Which groups of columns each effect changes, relative to the same scenario
// and seed without it (physics-effects.md, "what happens in the world").
TEST(Simulator, EachEffectChangesExactlyItsColumns) {
  Scenario sc;  // default, noisy sensors: the noise streams must not shift either
  sc.seed = 11;
  sc.sensors.encoders.omega = true;
  sc.motion.segments = {stop(0.5),    straight(2, 0.5), arc(0.8, 90, 0.4),
                        spin(90, 60), straight(1, 0.4), stop(0.5)};
  const tracks::Track base = simulate(sc);
  struct Group {
    const char* name;
    std::vector<tracks::Col> cols;
    bool ticks;
  };
  const std::vector<Group> groups = {
      {"ticks", {}, true},
      {"omega", {tracks::Col::omega_l, tracks::Col::omega_r}, false},
      {"cmd", {tracks::Col::v_cmd, tracks::Col::w_cmd}, false},
      {"gyro", {tracks::Col::gyro_z}, false},
      {"power", {tracks::Col::power_l, tracks::Col::power_r}, false},
      {"v_ext", {tracks::Col::v_ext}, false},
      {"w_ext", {tracks::Col::w_ext}, false},
      {"aps", {tracks::Col::aps_x, tracks::Col::aps_y}, false},
      {"gt", {tracks::Col::gt_x, tracks::Col::gt_y, tracks::Col::gt_theta}, false}};
  const std::string wheels_and_world = "gyro power v_ext w_ext aps gt";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"radius_error:scale_l=0.99,scale_r=1.01", wheels_and_world},
      {"wheel_base_error:scale=1.05", "gyro power w_ext aps gt"},  // v = (g_r + g_l)/2 does not see D
      {"radius_step:t=2,scale_l=1.01,scale_r=1.02", wheels_and_world},
      {"speed_radius:c=0.05", wheels_and_world},
      {"lateral_skid:k=0.05", "aps gt"},  // v and w unchanged: only the pose
      {"longitudinal_slip:k=0.1", wheels_and_world},
      // Power sees the slip zone only as a one-step jump of the body speed on
      // entry and exit (it depends on wheel rates and body accelerations), which
      // may fall between samples: power is not compared for it.
      {"slip_zone:x0=0.5,x1=1.5,y0=-1,y1=1,s_l=0.1,s_r=0.2", "gyro v_ext w_ext aps gt"},
      {"gyro_bias:b=0.01", "gyro"},
      {"gyro_scale:s=1.02", "gyro"},
      {"actuator_lag:tau=0.1", "ticks omega " + wheels_and_world},  // everything but the commands
      {"time_offset:dt=0.02", "ticks omega cmd"},
      {"odometry_bias:b_v=0.01,b_w=-0.02", "ticks omega cmd"},  // the odometry only
  };
  ASSERT_EQ(cases.size(), effect_table().size());
  for (const auto& [spec, expected] : cases) {
    Scenario with = sc;
    apply_effect(with.effects, parse_effect_spec(spec));
    const tracks::Track tr = simulate(with);
    ASSERT_EQ(tr.t(), base.t()) << spec;
    std::string changed;
    for (const Group& g : groups) {
      if (spec.rfind("slip_zone", 0) == 0 && std::string(g.name) == "power") continue;
      bool differs = g.ticks ? (tr.ticks_l() != base.ticks_l() || tr.ticks_r() != base.ticks_r()) : false;
      for (tracks::Col c : g.cols)
        for (std::size_t i = 0; i < tr.size(); ++i)
          differs = differs || (tr.at(c, i) && tr.col(c)[i] != base.col(c)[i]);
      if (!differs) continue;
      if (!changed.empty()) changed.push_back(' ');
      changed.append(g.name);
    }
    EXPECT_EQ(changed, expected) << spec;
  }
}

TEST(Simulator, SameSeedSameTrackDifferentSeedDifferentNoise) {
  Scenario sc;  // default (noisy) sensors
  sc.motion.segments = {straight(2, 0.5), arc(0.5, 180, 0.3), stop(1)};
  sc.effects.lateral_skid = Effects::LateralSkid{0.02};
  const std::string one = text_of(simulate(sc));
  EXPECT_EQ(one, text_of(simulate(sc)));
  Scenario other = sc;
  other.seed = sc.seed + 1;
  const tracks::Track a = simulate(sc), b = simulate(other);
  EXPECT_NE(one, text_of(b));
  EXPECT_EQ(a.ticks_l(), b.ticks_l());
  EXPECT_EQ(a.col(tracks::Col::gt_x), b.col(tracks::Col::gt_x));
  EXPECT_NE(a.col(tracks::Col::gyro_z), b.col(tracks::Col::gyro_z));
  std::size_t differ = 0, fixes = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a.at(tracks::Col::aps_x, i))
      ++fixes, differ += a.col(tracks::Col::aps_x)[i] != b.col(tracks::Col::aps_x)[i];
  EXPECT_EQ(differ, fixes);
  EXPECT_GE(fixes, 5u);
}

TEST(Simulator, NoiseHasTheConfiguredSize) {
  Scenario sc = quiet({stop(1), straight(10, 0.5), spin(720, 60), stop(1)});
  sc.sensors.aps.rate_hz = 100;
  sc.sensors.aps.sigma_m = 0.06;
  sc.sensors.aps.resolution_m = 1e-4;
  sc.sensors.gyro.sigma_rad_s = 0.002;
  const double tol = 0.04;  // > 3 sigma of a sample std over ~4000 samples
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    sc.seed = seed;
    const tracks::Track tr = simulate(sc);
    double sx = 0, sy = 0, sxx = 0, syy = 0, sg = 0, sgg = 0;
    double n = 0;
    for (std::size_t i = 0; i < tr.size(); ++i) {
      const double ex = tr.col(tracks::Col::aps_x)[i] - tr.col(tracks::Col::gt_x)[i];
      const double ey = tr.col(tracks::Col::aps_y)[i] - tr.col(tracks::Col::gt_y)[i];
      const double eg = tr.col(tracks::Col::gyro_z)[i] - tr.col(tracks::Col::w_ext)[i];
      sx += ex, sy += ey, sxx += ex * ex, syy += ey * ey, sg += eg, sgg += eg * eg, n += 1;
    }
    ASSERT_GT(n, 3000);
    EXPECT_NEAR(std::sqrt(sxx / n - (sx / n) * (sx / n)), 0.06, 0.06 * tol) << seed;
    EXPECT_NEAR(std::sqrt(syy / n - (sy / n) * (sy / n)), 0.06, 0.06 * tol) << seed;
    EXPECT_NEAR(sx / n, 0.0, 4 * 0.06 / std::sqrt(n)) << seed;
    EXPECT_NEAR(std::sqrt(sgg / n - (sg / n) * (sg / n)), 0.002, 0.002 * tol) << seed;
  }
}

TEST(Simulator, PowerFollowsTheMotorModel) {
  Scenario sc = quiet({straight(4, 0.5)});
  const tracks::Track tr = simulate(sc);
  const RobotParams r;
  // Cruise: tau = b_v*omega + tau_c*tanh(omega/omega_eps); P = tau*omega + (tau/k_t)^2*R.
  const std::size_t i = row_at_time(tr, 4.0);
  const double om = tr.col(tracks::Col::omega_l)[i];
  EXPECT_NEAR(om, 0.5 / 0.05, 1e-9);
  const double tau = r.viscous_friction_nm_s * om +
                     r.coulomb_friction_nm * std::tanh(om / r.coulomb_smoothing_rad_s);
  const double p = tau * om + std::pow(tau / r.torque_constant_nm_per_a, 2) * r.coil_resistance_ohm;
  EXPECT_NEAR(tr.col(tracks::Col::power_l)[i], p, 1e-9);
  EXPECT_NEAR(tr.col(tracks::Col::power_r)[i], p, 1e-9);
  // Accelerating costs more than cruising at the same speed; braking returns energy.
  const std::size_t acc = row_at_time(tr, 0.9), brake = row_at_time(tr, 8.5);  // ramps: 0-1 s and 8-9 s
  EXPECT_GT(tr.col(tracks::Col::power_l)[acc], tr.col(tracks::Col::power_l)[i] * 1.5);
  EXPECT_LT(tr.col(tracks::Col::power_l)[brake], tr.col(tracks::Col::power_l)[i]);
}

TEST(Simulator, StartPoseMovesTheWorldPathRigidlyAndNothingElse) {
  const Scenario origin = quiet({stop(0.5), straight(2, 0.5), arc(0.6, 150, 0.4), spin(-200, 90),
                                 straight(-1, 0.3)});
  Scenario moved = origin;
  moved.motion.start_x_m = 1, moved.motion.start_y_m = -2, moved.motion.start_theta_rad = 0.7;
  const tracks::Track a = simulate(origin), b = simulate(moved);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(b.col(tracks::Col::gt_x)[0], 1.0);
  EXPECT_EQ(b.col(tracks::Col::gt_y)[0], -2.0);
  EXPECT_EQ(b.col(tracks::Col::gt_theta)[0], 0.7);
  const double c = std::cos(0.7), s = std::sin(0.7);
  double max_pos = 0, max_th = 0, max_aps = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double x = a.col(tracks::Col::gt_x)[i], y = a.col(tracks::Col::gt_y)[i];
    max_pos = std::max(max_pos, std::hypot(b.col(tracks::Col::gt_x)[i] - (1 + c * x - s * y),
                                           b.col(tracks::Col::gt_y)[i] - (-2 + s * x + c * y)));
    max_th = std::max(max_th,
                      std::abs(b.col(tracks::Col::gt_theta)[i] - (a.col(tracks::Col::gt_theta)[i] + 0.7)));
    if (a.at(tracks::Col::aps_x, i))  // the same fix noise, added to the moved truth
      max_aps = std::max(max_aps, std::abs((b.col(tracks::Col::aps_x)[i] - b.col(tracks::Col::gt_x)[i]) -
                                           (a.col(tracks::Col::aps_x)[i] - a.col(tracks::Col::gt_x)[i])));
  }
  EXPECT_GT(std::abs(a.col(tracks::Col::gt_theta).back()), 0.5);  // the path turns, so the rotation matters
  EXPECT_LT(max_pos, 1e-9);
  EXPECT_LT(max_th, 1e-10);
  EXPECT_LT(max_aps, 1e-9);
  EXPECT_EQ(a.ticks_l(), b.ticks_l());
  EXPECT_EQ(a.ticks_r(), b.ticks_r());
  for (tracks::Col col :
       {tracks::Col::omega_l, tracks::Col::omega_r, tracks::Col::v_cmd, tracks::Col::w_cmd, tracks::Col::gyro_z,
        tracks::Col::power_l, tracks::Col::power_r, tracks::Col::v_ext, tracks::Col::w_ext})
    EXPECT_EQ(a.col(col), b.col(col)) << static_cast<int>(col);
  moved.motion.start_theta_rad = std::nan("");
  std::string why;
  EXPECT_FALSE(validate_scenario(moved, &why));
  EXPECT_THAT(why, HasSubstr("motion.start.theta_rad = nan"));
}

TEST(Simulator, LastRowIsCompleteAndAtRest) {
  Scenario sc;
  sc.motion.segments = {straight(1.234, 0.5)};
  const tracks::Track tr = simulate(sc);
  const std::size_t n = tr.size() - 1;
  EXPECT_TRUE(tr.at(tracks::Col::aps_x, n));
  EXPECT_TRUE(tr.at(tracks::Col::v_ext, n));
  EXPECT_EQ(tr.col(tracks::Col::v_cmd)[n], 0.0);
  EXPECT_EQ(tr.meta().origin, "simulated");
  EXPECT_EQ(tr.meta().get("sim.seed"), "1");
  EXPECT_EQ(tr.meta().get("sim.aps_sigma_m"), "0.06");
  EXPECT_EQ(tr.meta().get("sim.effects"), "none");
}

TEST(Simulator, InvalidScenariosNameTheBadField) {
  const auto why = [](const Scenario& sc) {
    std::string w;
    EXPECT_FALSE(validate_scenario(sc, &w));
    EXPECT_EQ(w.find('\n'), std::string::npos);
    return w;
  };
  Scenario sc;
  sc.motion.segments = {straight(1, 0.5)};
  std::string w;
  ASSERT_TRUE(validate_scenario(sc, &w)) << w;

  Scenario a = sc;
  a.robot.ticks_per_rev = 0;
  EXPECT_THAT(why(a), HasSubstr("robot.ticks_per_rev = 0"));
  Scenario b = sc;
  b.sensors.gyro.rate_hz = 300;
  EXPECT_THAT(why(b), HasSubstr("sensors.gyro.rate_hz = 300"));
  Scenario c = sc;
  c.step_s = 0.0007;
  EXPECT_THAT(why(c), HasSubstr("step_s = 0.0007"));
  Scenario d = sc;
  d.motion.segments.push_back(arc(-1, 90, 0.5));
  EXPECT_THAT(why(d), HasSubstr("radius_m = -1"));
  Scenario e = sc;
  e.sensors.aps.sigma_m = -0.1;
  EXPECT_THAT(why(e), HasSubstr("sensors.aps.sigma_m = -0.1"));
  Scenario f = sc;
  f.motion.segments = {stop(1e6)};
  EXPECT_THAT(why(f), HasSubstr("at most"));
  EXPECT_THROW((void)simulate(a), std::invalid_argument);
}

// --- motion profile ----------------------------------------------------------

MotionParams motion(std::vector<Segment> segs, double acc = 0.5, double ang = 2.0) {
  MotionParams m;
  m.max_accel_m_s2 = acc;
  m.max_angular_accel_rad_s2 = ang;
  m.segments = std::move(segs);
  return m;
}

TEST(MotionProfile, RespectsLimitsAndMeetsTheGeometry) {
  const std::vector<Segment> segs = {straight(2, 0.6),    arc(0.7, 90, 0.4),  spin(-180, 120), stop(2),
                                     straight(0.05, 1.0),  // too short for its speed: lowered
                                     arc(0.3, -45, 0.3),  straight(-0.5, 0.3)};
  const MotionParams m = motion(segs);
  const MotionProfile p(m);
  const double h = 1e-4;
  double dist = 0, angle = 0;
  Command prev = p.at(0);
  EXPECT_EQ(prev.v_m_s, 0.0);
  EXPECT_EQ(prev.w_rad_s, 0.0);
  for (double t = h; t <= p.duration_s() + h; t += h) {
    const Command c = p.at(t);
    EXPECT_LE(std::abs(c.v_m_s - prev.v_m_s) / h, m.max_accel_m_s2 * (1 + 1e-6)) << t;
    EXPECT_LE(std::abs(c.w_rad_s - prev.w_rad_s) / h, m.max_angular_accel_rad_s2 * (1 + 1e-6)) << t;
    dist += 0.5 * (c.v_m_s + prev.v_m_s) * h;  // signed: reversing counts negative
    angle += 0.5 * (c.w_rad_s + prev.w_rad_s) * h;
    prev = c;
  }
  EXPECT_EQ(prev.v_m_s, 0.0);
  double want_dist = 0, want_angle = 0;
  for (const auto& s : segs) {
    if (s.kind == Segment::Kind::straight) want_dist += s.distance_m;
    if (s.kind == Segment::Kind::arc) want_dist += s.radius_m * std::abs(s.angle_deg) * std::numbers::pi / 180;
    if (s.kind != Segment::Kind::stop)
      want_angle += s.kind == Segment::Kind::straight ? 0 : s.angle_deg * std::numbers::pi / 180;
  }
  EXPECT_NEAR(dist, want_dist, 1e-6);
  EXPECT_NEAR(angle, want_angle, 1e-6);
  // The short straight could not reach 1 m/s.
  ASSERT_EQ(p.plan().size(), segs.size());
  EXPECT_LT(p.plan()[4].speed_scale, 1.0);
  EXPECT_LT(p.plan()[4].v_m_s, 1.0);
  EXPECT_EQ(p.plan()[0].speed_scale, 1.0);
  // The stop keeps the robot at rest for its full 2 s.
  double rest = 0;
  for (double t = p.plan()[3].begin_s - 1; t <= p.plan()[3].end_s + 1; t += h) {
    const Command c = p.at(t);
    if (c.v_m_s == 0.0 && c.w_rad_s == 0.0) rest += h;
  }
  EXPECT_NEAR(rest, 2.0, 2 * h);
}

TEST(MotionProfile, CruisesAtTheCommandedSpeeds) {
  const MotionProfile p(motion({straight(4, 0.5), arc(1.0, -90, 0.4)}));
  const auto& plan = p.plan();
  const Command a = p.at(0.5 * (plan[0].begin_s + plan[0].end_s));
  EXPECT_DOUBLE_EQ(a.v_m_s, 0.5);
  EXPECT_DOUBLE_EQ(a.w_rad_s, 0.0);
  const Command b = p.at(0.5 * (plan[1].begin_s + plan[1].end_s));
  EXPECT_DOUBLE_EQ(b.v_m_s, 0.4);
  EXPECT_DOUBLE_EQ(b.w_rad_s, -0.4);
}

TEST(MotionProfile, BadSegmentsAreNamed) {
  try {
    MotionProfile p(motion({straight(1, 0.5), spin(90, 0)}));
    FAIL();
  } catch (const ProfileError& e) {
    EXPECT_EQ(e.segment(), 1u);
    EXPECT_THAT(e.what(), HasSubstr("segment 2 (spin): rate_deg_s = 0"));
  }
  EXPECT_THROW(MotionProfile(motion({straight(1, 0.5)}, 0.0)), ProfileError);
  EXPECT_EQ(MotionProfile(motion({})).duration_s(), 0.0);
}

}  // namespace
}  // namespace odotune::sim

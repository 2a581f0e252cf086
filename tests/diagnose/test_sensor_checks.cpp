// Sensor checks (odotune/diagnose/sensor_checks.h) on synthetic recordings whose
// truth is known: a robot driven by smooth commands, integrated at 1 ms,
// with a gyro of known scale/bias, wheels of known true radii / base, an
// optional odometry time offset and actuator lag, and ground truth or fixes.
// Everything here is generated in the test (no simulator, no track files).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/diagnose/sensor_checks.h>
#include <odotune/sim/normal_rng.h>
#include <odotune/sim/simulator.h>

#include "concealed_cases.h"

namespace odotune::diagnose {
namespace {

struct SensorTruth {
  double gyro_s = 1.0, gyro_b = 0.0, gyro_sigma = 0.002;
  double scale_l = 1.0, scale_r = 1.0, base_scale = 1.0;  // true / nominal
  double time_offset_s = 0.0;                             // odometry stamped t measured at t − dt
  double act_tau_s = 0.0;                                 // body follows the commands through a 1st-order lag
  bool aps = false;                                       // fixes only (1 Hz) instead of ground truth (100 Hz)
  double aps_sigma_m = 0.03;
  double gt_sigma_m = 0.0, gt_sigma_rad = 0.0;
  double ticks_per_rev = 4000;  // encoder quantisation (0 = none)
  double duration_s = 120.0;
  std::uint64_t seed = 1;
};

constexpr double kR = 0.08, kD = 0.42;  // nominal radius and base [m]

// Commanded motion: smooth, both turn directions, speeds 0.15–0.75 m/s.
double cmd_v(double t) {
  return 0.45 + 0.3 * std::sin(2 * std::numbers::pi * t / 17.0) * std::min(1.0, t / 3.0);
}
double cmd_w(double t) {
  return (0.9 * std::sin(2 * std::numbers::pi * t / 11.0 + 0.3) +
          0.35 * std::sin(2 * std::numbers::pi * t / 4.3)) *
         std::min(1.0, t / 3.0);
}

double interp(const std::vector<double>& y, double h, double t) {
  const double u = std::clamp(t / h, 0.0, static_cast<double>(y.size() - 1));
  const std::size_t i = std::min(static_cast<std::size_t>(u), y.size() - 2);
  return y[i] + (y[i + 1] - y[i]) * (u - static_cast<double>(i));
}

// Wheel angle as an encoder reports it (whole counts).
double quantise(double phi_rad, double ticks_per_rev) {
  if (ticks_per_rev <= 0) return phi_rad;
  const double tick = 2 * std::numbers::pi / ticks_per_rev;
  return std::floor(phi_rad / tick) * tick;
}

DiagInput make_input(const SensorTruth& tr) {
  const double h = 1e-3;
  const std::size_t n = static_cast<std::size_t>(std::round(tr.duration_s / h)) + 1;
  std::vector<double> x(n), y(n), th(n), w(n), pl(n), pr(n), cv(n), cw(n);
  const double Rl = kR * tr.scale_l, Rr = kR * tr.scale_r, D = kD * tr.base_scale;
  const double a = tr.act_tau_s > 0 ? 1.0 - std::exp(-h / tr.act_tau_s) : 1.0;
  double v_true = 0.0, w_true = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * h;
    cv[k] = cmd_v(t), cw[k] = cmd_w(t);
    v_true += (cv[k] - v_true) * a;
    w_true += (cw[k] - w_true) * a;
    w[k] = w_true;
    if (k + 1 < n) {
      const double mid = th[k] + 0.5 * w_true * h;
      x[k + 1] = x[k] + v_true * std::cos(mid) * h;
      y[k + 1] = y[k] + v_true * std::sin(mid) * h;
      th[k + 1] = th[k] + w_true * h;
      pl[k + 1] = pl[k] + (v_true - w_true * D / 2) / Rl * h;
      pr[k + 1] = pr[k] + (v_true + w_true * D / 2) / Rr * h;
    }
  }
  sim::Normal gyro_noise(sim::splitmix64(tr.seed)), ref_noise(sim::splitmix64(tr.seed + 100));
  DiagInput in;
  in.track_name = "synthetic";
  in.radius_l_m = in.radius_r_m = kR;
  in.wheel_base_m = kD;
  const double dt = 0.01;
  for (double t = 0.0; t <= tr.duration_s + 1e-9; t += dt) {
    in.odo_t_s.push_back(t);
    in.phi_l_rad.push_back(quantise(interp(pl, h, t - tr.time_offset_s), tr.ticks_per_rev));
    in.phi_r_rad.push_back(quantise(interp(pr, h, t - tr.time_offset_s), tr.ticks_per_rev));
    in.cmd_v_mps.push_back(interp(cv, h, t - tr.time_offset_s));
    in.cmd_w_radps.push_back(interp(cw, h, t - tr.time_offset_s));
    in.gyro_t_s.push_back(t);
    in.gyro_z_radps.push_back(tr.gyro_s * interp(w, h, t) + tr.gyro_b + tr.gyro_sigma * gyro_noise());
  }
  if (tr.aps) {
    in.reference = ReferenceKind::aps;
    in.ref_sigma_m = tr.aps_sigma_m;
    for (double t = 0.0; t <= tr.duration_s + 1e-9; t += 1.0) {
      in.ref_t_s.push_back(t);
      in.ref_x_m.push_back(interp(x, h, t) + tr.aps_sigma_m * ref_noise());
      in.ref_y_m.push_back(interp(y, h, t) + tr.aps_sigma_m * ref_noise());
    }
  } else {
    in.reference = ReferenceKind::gt;
    in.ref_sigma_m = tr.gt_sigma_m;
    for (double t = 0.0; t <= tr.duration_s + 1e-9; t += dt) {
      in.ref_t_s.push_back(t);
      in.ref_x_m.push_back(interp(x, h, t) + tr.gt_sigma_m * ref_noise());
      in.ref_y_m.push_back(interp(y, h, t) + tr.gt_sigma_m * ref_noise());
      in.ref_theta_rad.push_back(interp(th, h, t) + tr.gt_sigma_rad * ref_noise());
    }
  }
  return in;
}

TEST(SensorChecks, OptionsValidation) {
  std::string why;
  EXPECT_TRUE(SensorCheckOptions{}.IsValid(&why)) << why;
  SensorCheckOptions o;
  o.bin_s = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("bin_s"), std::string::npos) << why;
  o = {};
  o.bootstrap_replicates = 1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("bootstrap_replicates"), std::string::npos) << why;
  o = {};
  o.lag_step_s = 1e-6;
  EXPECT_FALSE(o.IsValid(&why));
  DiagInput in = make_input(SensorTruth{.duration_s = 20});
  EXPECT_THROW(check_sensors(in, o), std::invalid_argument);
}

TEST(SensorChecks, InconsistentInputIsOneClearError) {
  DiagInput in = make_input(SensorTruth{.duration_s = 20});
  in.gyro_z_radps.pop_back();
  try {
    check_sensors(in);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("synthetic"), std::string::npos) << msg;
    EXPECT_NE(msg.find("gyro"), std::string::npos) << msg;
  }
  in = make_input(SensorTruth{.duration_s = 20});
  in.ref_t_s[10] = in.ref_t_s[9];
  EXPECT_THROW(check_sensors(in), std::invalid_argument);
}

TEST(SensorChecks, ReferenceRatesMatchTheTruth) {
  const DiagInput in = make_input(SensorTruth{.duration_s = 40});
  const ReferenceBins rb = reference_bins(in, SensorCheckOptions{});
  ASSERT_GT(rb.t0_s.size(), 100u);
  ASSERT_TRUE(rb.heading);
  for (std::size_t i = 0; i < rb.t0_s.size(); ++i) {
    EXPECT_GE(rb.t1_s[i] - rb.t0_s[i], 0.25 - 1e-9);
    // Mean of the commands over the bin (no lag here): a bin average of a
    // smooth function, compared with the reference's central difference.
    double mv = 0, mw = 0;
    const int m = 50;
    for (int k = 0; k < m; ++k) {
      const double t = rb.t0_s[i] + (k + 0.5) * (rb.t1_s[i] - rb.t0_s[i]) / m;
      mv += cmd_v(t) / m, mw += cmd_w(t) / m;
    }
    EXPECT_NEAR(rb.w_radps[i], mw, 2e-3) << "bin " << i;
    EXPECT_NEAR(rb.v_mps[i], mv, 2e-3) << "bin " << i;
  }
  // A time range: bins inside it only, contiguous.
  const ReferenceBins part = reference_bins(in, SensorCheckOptions{}, 10.0, 20.0);
  ASSERT_GT(part.t0_s.size(), 30u);
  EXPECT_GE(part.t0_s.front(), 10.0);
  EXPECT_LE(part.t1_s.back(), 20.0);
  for (std::size_t i = 1; i < part.t0_s.size(); ++i) EXPECT_EQ(part.t0_s[i], part.t1_s[i - 1]);
}

TEST(SensorChecks, GyroScaleAndBiasRecovered) {
  for (const bool noisy_gt : {false, true}) {
    SensorTruth tr{.gyro_s = 1.015, .gyro_b = 0.004, .seed = 7};
    if (noisy_gt) tr.gt_sigma_m = 0.002, tr.gt_sigma_rad = 0.003;
    const SensorCheck sc = check_sensors(make_input(tr));
    const GyroCheck& g = sc.gyro;
    ASSERT_TRUE(g.available) << g.unavailable_reason;
    EXPECT_EQ(g.scale.name, "gyro_scale.s");
    EXPECT_EQ(g.bias.name, "gyro_bias.b");
    // Consistent with the stderr, and the stderr is informative.
    EXPECT_LT(std::abs(g.scale.value - tr.gyro_s), 4 * g.scale.std_error) << "noisy gt " << noisy_gt;
    EXPECT_LT(std::abs(g.bias.value - tr.gyro_b), 4 * g.bias.std_error) << "noisy gt " << noisy_gt;
    EXPECT_LT(g.scale.std_error, 0.002);
    EXPECT_LT(g.bias.std_error, 0.0005);
    EXPECT_GT(g.scale.std_error, 0.0);
    EXPECT_TRUE(g.scale.departs());
    EXPECT_TRUE(g.bias.departs());
    // Noise estimate from the samples: the injected 2 mrad/s.
    EXPECT_NEAR(g.noise_sigma_radps, 0.002, 0.0003);
    EXPECT_NEAR(g.bias.drift, std::abs(g.bias.value) * 20.0, 1e-12);
  }
}

// The gyro regression's own finer bins keep more reference headings: a
// noisy heading reference pins the bias down better than with 0.25 s bins.
TEST(SensorChecks, GyroBinsKeepMoreHeadingsAndShrinkTheBiasError) {
  SensorTruth tr{.gyro_b = 0.0005, .seed = 11};
  tr.gt_sigma_m = 0.002, tr.gt_sigma_rad = 0.015;
  const DiagInput in = make_input(tr);
  const SensorCheck fine = check_sensors(in);
  SensorCheckOptions o;
  o.gyro_bin_s = o.bin_s;  // the reference bins of the other checks
  const SensorCheck coarse = check_sensors(in, o);
  ASSERT_TRUE(fine.gyro.available && coarse.gyro.available);
  EXPECT_EQ(coarse.gyro.bins, static_cast<int>(coarse.reference.t0_s.size()));
  EXPECT_GT(fine.gyro.bins, 4 * coarse.gyro.bins);                        // 0.05 s against 0.25 s
  EXPECT_LT(fine.gyro.bias.std_error, 0.9 * coarse.gyro.bias.std_error);  // 0.78 here
  EXPECT_LT(std::abs(fine.gyro.bias.value - 0.0005), 4 * fine.gyro.bias.std_error);
  SensorCheckOptions bad;
  bad.gyro_bin_s = 0.0;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("gyro_bin_s"), std::string::npos) << why;
}

TEST(SensorChecks, RelevanceGateSeparatesSignificantFromRelevant) {
  const DiagInput in = make_input(SensorTruth{.gyro_b = 0.001, .seed = 3});
  SensorCheckOptions o;
  const GyroCheck g = check_sensors(in, o).gyro;
  ASSERT_TRUE(g.available);
  EXPECT_TRUE(g.bias.significant);
  EXPECT_TRUE(g.bias.departs());
  o.relevance_factor = 1e4;  // demand a drift far beyond any bias here
  const GyroCheck g2 = check_sensors(in, o).gyro;
  EXPECT_TRUE(g2.bias.significant);
  EXPECT_FALSE(g2.bias.relevant);
  EXPECT_FALSE(g2.bias.departs());
}

double mean(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m += x;
  return m / static_cast<double>(v.size());
}
// Sample standard deviation.
double spread(const std::vector<double>& v) {
  const double m = mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

// No effect: over 20 seeds at most one departure per tested quantity.
TEST(SensorChecks, NoEffectGivesNoVerdictOverSeeds) {
  int gyro_fp = 0, speed_fp = 0, yaw_fp = 0, lag_bad = 0;
  // Per group (0: exact ground truth, 1: noisy ground truth): estimates and
  // their bootstrap stderr, to check the stderr is neither too small (false
  // positives) nor so inflated that the test above could never fail.
  std::vector<double> s_val[2], s_se[2], b_val[2], b_se[2];
  for (std::uint64_t seed = 100; seed < 120; ++seed) {
    SensorTruth tr{.duration_s = 90, .seed = seed};
    if (seed % 2 == 1) tr.gt_sigma_m = 0.002, tr.gt_sigma_rad = 0.003;  // half with noisy GT
    SensorCheckOptions o;
    o.seed = seed;
    o.bootstrap_replicates = 100;
    const SensorCheck sc = check_sensors(make_input(tr), o);
    ASSERT_TRUE(sc.gyro.available);
    ASSERT_TRUE(sc.odometry.available);
    gyro_fp += (sc.gyro.scale.departs() || sc.gyro.bias.departs()) ? 1 : 0;
    const int group = static_cast<int>(seed % 2);
    s_val[group].push_back(sc.gyro.scale.value), s_se[group].push_back(sc.gyro.scale.std_error);
    b_val[group].push_back(sc.gyro.bias.value), b_se[group].push_back(sc.gyro.bias.std_error);
    speed_fp += sc.odometry.speed_ratio.departs() ? 1 : 0;

    yaw_fp += sc.odometry.yaw_ratio.departs() ? 1 : 0;
    ASSERT_TRUE(sc.odometry.odometry_late.available);
    lag_bad += std::abs(sc.odometry.odometry_late.lag_s) > 0.005 ? 1 : 0;
  }
  EXPECT_LE(gyro_fp, 1);
  for (int group = 0; group < 2; ++group) {
    const double s_ratio = spread(s_val[group]) / mean(s_se[group]);
    const double b_ratio = spread(b_val[group]) / mean(b_se[group]);
    EXPECT_GT(s_ratio, 0.3) << "group " << group;
    EXPECT_LT(s_ratio, 2.5) << "group " << group;
    EXPECT_GT(b_ratio, 0.3) << "group " << group;
    EXPECT_LT(b_ratio, 2.5) << "group " << group;
  }
  EXPECT_LE(speed_fp, 1);
  EXPECT_LE(yaw_fp, 1);
  EXPECT_LE(lag_bad, 1);
}

TEST(SensorChecks, WheelRatiosReflectRadiusAndBase) {
  const SensorTruth tr{.scale_l = 1.012, .scale_r = 1.012, .base_scale = 1.05, .seed = 11};
  const OdometryCheck oc = check_sensors(make_input(tr)).odometry;
  ASSERT_TRUE(oc.available) << oc.unavailable_reason;
  // True ground travel = R_true·φ = 1.012 × odometry; true yaw = 1.012/1.05 × odometry yaw.
  EXPECT_NEAR(oc.speed_ratio.value, 1.012, std::max(4 * oc.speed_ratio.std_error, 5e-4));
  EXPECT_NEAR(oc.yaw_ratio.value, 1.012 / 1.05, std::max(4 * oc.yaw_ratio.std_error, 1e-3));
  EXPECT_TRUE(oc.speed_ratio.departs());
  EXPECT_TRUE(oc.yaw_ratio.departs());
  EXPECT_LT(oc.speed_ratio.std_error, 0.002);
}

TEST(SensorChecks, OdometryTimeOffsetRecoveredAsLateOdometry) {
  for (const double dt : {0.06, -0.035}) {
    const SensorTruth tr{.time_offset_s = dt, .seed = 5};
    const OdometryCheck oc = check_sensors(make_input(tr)).odometry;
    ASSERT_TRUE(oc.odometry_late.available);
    EXPECT_FALSE(oc.odometry_late.at_edge);
    EXPECT_NEAR(oc.odometry_late.lag_s, dt, 0.004) << "dt " << dt;
    EXPECT_LT(std::abs(oc.odometry_late.lag_s - dt), 4 * oc.odometry_late.std_error_s + 0.002);
    EXPECT_GT(oc.odometry_late.peak_correlation, 0.99);
    // The commands are odometry columns too: shifted with them, so the body
    // appears to lead them by dt.
    ASSERT_TRUE(oc.command_delay.available);
    EXPECT_NEAR(oc.command_delay.lag_s, -dt, 0.006);
  }
}

TEST(SensorChecks, ActuatorLagShowsAsCommandDelayNotLateOdometry) {
  const SensorTruth tr{.act_tau_s = 0.15, .seed = 9};
  const OdometryCheck oc = check_sensors(make_input(tr)).odometry;
  ASSERT_TRUE(oc.command_delay.available);
  // A first-order lag delays these slow sinusoids by atan(ωτ)/ω ≈ 0.148 s.
  EXPECT_NEAR(oc.command_delay.lag_s, 0.15, 0.015);
  // Encoders measure the actual wheel rotation: no lag against the reference.
  EXPECT_NEAR(oc.odometry_late.lag_s, 0.0, 0.004);
}

TEST(SensorChecks, FixesOnlyReference) {
  const SensorTruth tr{.gyro_b = 0.01,
                       .scale_l = 1.03,
                       .scale_r = 1.03,
                       .aps = true,
                       .aps_sigma_m = 0.03,
                       .duration_s = 240,
                       .seed = 21};
  const SensorCheck sc = check_sensors(make_input(tr));
  EXPECT_FALSE(sc.gyro.available);
  EXPECT_NE(sc.gyro.unavailable_reason.find("heading"), std::string::npos);
  EXPECT_FALSE(sc.reference.heading);
  EXPECT_TRUE(sc.reference.w_radps.empty());
  for (std::size_t i = 0; i < sc.reference.t0_s.size(); ++i) {
    EXPECT_GE(sc.reference.t1_s[i] - sc.reference.t0_s[i], 2.0 - 1e-9);
  }
  const OdometryCheck& oc = sc.odometry;
  ASSERT_TRUE(oc.available) << oc.unavailable_reason;
  EXPECT_LT(std::abs(oc.speed_ratio.value - 1.03), 4 * oc.speed_ratio.std_error);
  EXPECT_LT(oc.speed_ratio.std_error, 0.01);
  EXPECT_TRUE(oc.speed_ratio.departs())
      << "ratio " << oc.speed_ratio.value << " se " << oc.speed_ratio.std_error << " drift "
      << oc.speed_ratio.drift << " noise drift " << oc.speed_ratio.noise_drift;
  EXPECT_FALSE(std::isfinite(oc.yaw_ratio.value));
}

TEST(SensorChecks, FixesOnlyNoEffectNoDeparture) {
  int fp = 0;
  for (std::uint64_t seed = 200; seed < 210; ++seed) {
    const SensorTruth tr{.aps = true, .aps_sigma_m = 0.06, .duration_s = 180, .seed = seed};
    SensorCheckOptions o;
    o.seed = seed;
    o.bootstrap_replicates = 100;
    const OdometryCheck oc = check_sensors(make_input(tr), o).odometry;
    ASSERT_TRUE(oc.available);
    fp += oc.speed_ratio.departs() ? 1 : 0;
  }
  EXPECT_LE(fp, 1);
}

TEST(SensorChecks, MissingGyroAndRadiiAreReportedNotThrown) {
  DiagInput in = make_input(SensorTruth{.duration_s = 20});
  in.gyro_t_s.clear();
  in.gyro_z_radps.clear();
  in.radius_l_m = 0.0;
  const SensorCheck sc = check_sensors(in);
  EXPECT_FALSE(sc.gyro.available);
  EXPECT_EQ(sc.gyro.unavailable_reason, "no gyro");
  EXPECT_FALSE(sc.odometry.available);
  EXPECT_NE(sc.odometry.unavailable_reason.find("radii"), std::string::npos);
}

// ---- on the project's simulator (the concealed suite's robots) -----------

// A DiagInput read straight off a simulated Track (wheel angles from ticks,
// or the commands as body velocities; gyro; ground truth or fixes).
DiagInput from_track(const tracks::Track& tr, const concealed::CaseRobot& r) {
  DiagInput in;
  in.track_name = tr.name();
  in.radius_l_m = r.radius_l_m, in.radius_r_m = r.radius_r_m, in.wheel_base_m = r.wheel_base_m;
  in.odometry = tr.has_ticks() ? OdometryKind::wheel_angles : OdometryKind::body_velocity;
  const auto& t = tr.t();
  const double tick = 2 * std::numbers::pi / r.ticks_per_rev;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const bool odo = tr.has_ticks() ? tr.ticks_l()[i] != tracks::kNoTick : tr.at(tracks::Col::v_cmd, i);
    if (odo) {
      in.odo_t_s.push_back(t[i]);
      if (tr.has_ticks()) {
        in.phi_l_rad.push_back(tick * static_cast<double>(tr.ticks_l()[i] - tr.ticks_l()[0]));
        in.phi_r_rad.push_back(tick * static_cast<double>(tr.ticks_r()[i] - tr.ticks_r()[0]));
        in.cmd_v_mps.push_back(tr.col(tracks::Col::v_cmd)[i]);
        in.cmd_w_radps.push_back(tr.col(tracks::Col::w_cmd)[i]);
      } else {
        in.v_mps.push_back(tr.col(tracks::Col::v_cmd)[i]);
        in.w_radps.push_back(tr.col(tracks::Col::w_cmd)[i]);
      }
    }
    if (tr.at(tracks::Col::gyro_z, i))
      in.gyro_t_s.push_back(t[i]), in.gyro_z_radps.push_back(tr.col(tracks::Col::gyro_z)[i]);
    if (tr.at(tracks::Col::gt_x, i)) {
      in.ref_t_s.push_back(t[i]);
      in.ref_x_m.push_back(tr.col(tracks::Col::gt_x)[i]), in.ref_y_m.push_back(tr.col(tracks::Col::gt_y)[i]);
      in.ref_theta_rad.push_back(tr.col(tracks::Col::gt_theta)[i]);
    } else if (tr.at(tracks::Col::aps_x, i)) {
      in.reference = ReferenceKind::aps;
      in.ref_t_s.push_back(t[i]);
      in.ref_x_m.push_back(tr.col(tracks::Col::aps_x)[i]), in.ref_y_m.push_back(tr.col(tracks::Col::aps_y)[i]);
    }
  }
  return in;
}

const concealed::ConcealedCase& find_sensor_case(std::string_view name) {
  for (const auto& c : concealed::concealed_cases()) {
    if (c.name == name) return c;
  }
  throw std::invalid_argument("no case " + std::string(name));
}

SensorCheck check_case(std::string_view name) {
  const auto& c = find_sensor_case(name);
  return check_sensors(from_track(sim::simulate(concealed::base_scenario(c)), c.robot));
}

TEST(SensorChecksOnSimulator, GyroBiasBelowGyroNoiseIsFound) {
  const SensorCheck sc = check_case("gyro_bias_below_gyro_noise");  // b = 0.0007, 40 Hz, noisy GT
  ASSERT_TRUE(sc.gyro.available);
  EXPECT_LT(std::abs(sc.gyro.bias.value - 0.0007), 4 * sc.gyro.bias.std_error + 5e-5);
  EXPECT_TRUE(sc.gyro.bias.departs()) << "z " << sc.gyro.bias.z;
  EXPECT_FALSE(sc.gyro.scale.departs()) << "s " << sc.gyro.scale.value << " z " << sc.gyro.scale.z;
  EXPECT_FALSE(sc.odometry.speed_ratio.departs()) << sc.odometry.speed_ratio.value;
  EXPECT_FALSE(sc.odometry.yaw_ratio.departs()) << sc.odometry.yaw_ratio.value;
}

TEST(SensorChecksOnSimulator, WheelBaseErrorBlamesTheWheelsNotTheGyro) {
  const SensorCheck sc = check_case("wheel_base_error_with_heading");  // scale 0.9985
  ASSERT_TRUE(sc.gyro.available);
  EXPECT_FALSE(sc.gyro.scale.departs()) << "s " << sc.gyro.scale.value << " z " << sc.gyro.scale.z;
  EXPECT_FALSE(sc.gyro.bias.departs()) << "b " << sc.gyro.bias.value << " z " << sc.gyro.bias.z;
  // True yaw = wheel yaw / 0.9985.
  EXPECT_NEAR(sc.odometry.yaw_ratio.value, 1.0 / 0.9985, std::max(4 * sc.odometry.yaw_ratio.std_error, 2e-4));
}

TEST(SensorChecksOnSimulator, NoEffectNoDeparture) {
  for (const std::string_view name : {"none_indoor_gt", "none_commands_gt", "none_outdoor_fixes"}) {
    const SensorCheck sc = check_case(name);
    EXPECT_FALSE(sc.gyro.scale.departs()) << name << " z " << sc.gyro.scale.z;
    EXPECT_FALSE(sc.gyro.bias.departs()) << name << " z " << sc.gyro.bias.z;
    EXPECT_FALSE(sc.odometry.speed_ratio.departs()) << name << " z " << sc.odometry.speed_ratio.z;
    EXPECT_FALSE(sc.odometry.yaw_ratio.departs()) << name << " z " << sc.odometry.yaw_ratio.z;
    if (sc.reference.heading) {
      ASSERT_TRUE(sc.odometry.odometry_late.available) << name;
      EXPECT_NEAR(sc.odometry.odometry_late.lag_s, 0.0, 0.005) << name;
    }
  }
}

TEST(SensorChecksOnSimulator, LagsOfTimeOffsetAndActuatorLag) {
  // Encoders stamped 10 ms late.
  const SensorCheck late = check_case("time_offset_late_encoders");
  EXPECT_NEAR(late.odometry.odometry_late.lag_s, 0.01, 0.003);
  // Command odometry, body lagging 0.1 s behind: odometry leads (negative).
  const SensorCheck lag = check_case("actuator_lag_commands_only");
  EXPECT_NEAR(lag.odometry.odometry_late.lag_s, -0.1, 0.02);
  // Command odometry stamped 80 ms early: leads by a pure shift.
  const SensorCheck early = check_case("time_offset_early_commands");
  EXPECT_NEAR(early.odometry.odometry_late.lag_s, -0.08, 0.01);
}

}  // namespace
}  // namespace odotune::diagnose

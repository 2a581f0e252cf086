// The equivalent constant process-noise rate of the alpha/gyro models against
// closed forms on motions where R_k is known by hand, and the rq case.
#include <odotune/objectives/process_noise_rate.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <gtest/gtest.h>

#include <odotune/results/ros_export.h>

namespace odotune::objectives {
namespace {

constexpr double kD = 0.3;  // wheel base [m]

void expect_rel(double expected, double actual, double rel = 1e-9) {
  EXPECT_NEAR(actual, expected, rel * std::abs(expected)) << "expected " << expected;
}

// A replay input that drives straight along heading theta0 with wheel travel
// d_first on step 1 and d on steps 2..n, one step per dt; a position fix every
// `fix_every` rows, placed `fix_scale` times as far along the line as the
// odometry says (the true motion is longer): along-track innovations only.
ReplayInput straight_line(const std::string& name, double theta0, double d_first, double d, int n, double dt,
                          double fix_scale = 1.02, int fix_every = 50) {
  ReplayInput in;
  in.track_name = name;
  in.wheel_base_m = kD;
  in.initial_pose << 1.0, -2.0, theta0;
  in.t0_s = 3.0;
  double s = 0.0;  // odometry distance
  for (int k = 1; k <= n; ++k) {
    const double dk = k == 1 ? d_first : d;
    s += dk;
    ReplayRow row;
    row.t_s = in.t0_s + k * dt;
    row.step = static_cast<std::int32_t>(in.steps.size());
    in.steps.push_back({dk, dk});
    in.abs_yaw_rate_rad_s.push_back(0.0);
    if (k % fix_every == 0) {
      row.fix = static_cast<std::int32_t>(in.fixes.size());
      in.fixes.emplace_back(1.0 + fix_scale * s * std::cos(theta0), -2.0 + fix_scale * s * std::sin(theta0));
    }
    in.rows.push_back(row);
  }
  return in;
}

// Closed form of diag(R) for a straight step of travel d at heading θ with
// per-wheel variance var (σl² = σr²): V from the midpoint model with Δθ = 0,
//   V_x = (½c + ks, ½c − ks), V_y = (½s − kc, ½s + kc), V_θ = (−1/D, 1/D), k = d/(2D),
// so R_xx = var·(½c² + 2k²s²), R_yy = var·(½s² + 2k²c²), R_θθ = 2·var/D².
Eigen::Vector3d straight_R(double var, double d, double theta) {
  const double c = std::cos(theta), s = std::sin(theta), k = d / (2.0 * kD);
  return {var * (0.5 * c * c + 2 * k * k * s * s), var * (0.5 * s * s + 2 * k * k * c * c),
          2.0 * var / (kD * kD)};
}

TEST(ProcessNoiseRate, AlphaOnAStraightLineMatchesTheClosedForm) {
  const double theta0 = 0.5, d = 0.01, dt = 0.02;  // 0.5 m/s at 50 Hz
  const int n = 501;
  // Step 1 is much longer: it is left out of the average (its start time is unknown).
  const ReplayInput in = straight_line("line", theta0, 0.2, d, n, dt);
  filters::NoiseParams p;
  p.model = filters::NoiseModel::alpha;
  p.a1 = 0.05;
  p.a2 = 0.4;  // no effect: l = r
  const ProcessNoiseRate q = equivalent_process_noise_rate(p, std::span(&in, 1));

  EXPECT_EQ(q.steps, n - 1);
  expect_rel((n - 1) * dt, q.duration_s, 1e-12);
  expect_rel(50.0, q.odometry_rate_hz, 1e-12);
  // Per step: σl² = σr² = (α1·d)²; per second: × 50 steps/s.
  const Eigen::Vector3d R = straight_R(std::pow(p.a1 * d, 2), d, theta0);
  expect_rel(R(0) * 50.0, q.x_m2_per_s);
  expect_rel(R(1) * 50.0, q.y_m2_per_s);
  expect_rel(R(2) * 50.0, q.theta_rad2_per_s);
  // The heading matters (x and y differ at 0.5 rad): world-frame noise.
  EXPECT_GT(q.x_m2_per_s, 1.5 * q.y_m2_per_s);
  // R scales with α1²: doubling α1 quadruples the rate.
  p.a1 *= 2.0;
  const ProcessNoiseRate q2 = equivalent_process_noise_rate(p, std::span(&in, 1));
  expect_rel(4.0 * q.x_m2_per_s, q2.x_m2_per_s);
}

TEST(ProcessNoiseRate, GyroInPlaceRotationAveragesOverHeadings) {
  // Turning on the spot at w = π rad/s, 50 Hz: Δθ = 2π/100 per step; steps
  // 2..201 cover exactly two turns, so cos²θ and sin²θ average to ½.
  const double dt = 0.02, w = std::numbers::pi, b = 0.5 * w * kD * dt;  // each wheel's travel
  const int n = 201;
  ReplayInput in;
  in.track_name = "spin";
  in.wheel_base_m = kD;
  in.initial_pose << 0.0, 0.0, 0.3;
  for (int k = 1; k <= n; ++k) {
    ReplayRow row;
    row.t_s = k * dt;
    row.step = static_cast<std::int32_t>(in.steps.size());
    in.steps.push_back({-b, b});
    in.abs_yaw_rate_rad_s.push_back(w);
    if (k % 25 == 0) {
      row.fix = static_cast<std::int32_t>(in.fixes.size());
      in.fixes.emplace_back(0.0, 0.0);
    }
    in.rows.push_back(row);
  }
  filters::NoiseParams p;
  p.model = filters::NoiseModel::gyro;
  p.a1 = 0.02;
  p.a2 = 0.01;
  p.b1 = 0.03;
  p.b2 = 0.05;
  const ProcessNoiseRate q = equivalent_process_noise_rate(p, std::span(&in, 1));
  // α from eq. 6–7 with |ω| = π; l − r = −2b; σl² = σr² = (α1·b)² + (α2·2b)².
  const double a1 = p.a1 + p.b1 * w, a2 = p.a2 + p.b2 * w;
  const double var = std::pow(a1 * b, 2) + std::pow(2 * a2 * b, 2);
  // d = 0: V_x = (½c, ½c), V_y = (½s, ½s), V_θ = (−1/D, 1/D):
  // R_xx = ½·var·c², mean ¼·var; R_yy likewise; R_θθ = 2·var/D².
  expect_rel(0.25 * var * 50.0, q.x_m2_per_s, 1e-9);
  expect_rel(0.25 * var * 50.0, q.y_m2_per_s, 1e-9);
  expect_rel(2.0 * var / (kD * kD) * 50.0, q.theta_rad2_per_s, 1e-9);
  // Without the gyro terms it is clearly less.
  p.b1 = p.b2 = 0.0;
  EXPECT_LT(equivalent_process_noise_rate(p, std::span(&in, 1)).x_m2_per_s, 0.2 * q.x_m2_per_s);
}

TEST(ProcessNoiseRate, RqIsRTimesTheOdometryRateAsRosInputFromRq) {
  // Irregular sampling: steps alternate 10 ms and 30 ms, i.e. 50 steps/s on average.
  ReplayInput in = straight_line("irregular", 0.0, 0.01, 0.01, 301, 0.02);
  for (std::size_t k = 0; k < in.rows.size(); ++k)
    in.rows[k].t_s = 0.02 * static_cast<double>(k - k % 2) + (k % 2 ? 0.01 : 0.0);
  // rows at 0, 0.01, 0.04, 0.05, 0.08, …: from the first to the last step, 300 steps over 5.99 s.
  const double span_s = in.rows.back().t_s - in.rows.front().t_s;
  filters::NoiseParams p;
  p.model = filters::NoiseModel::rq;
  p.r_x_m2 = 40e-6;
  p.r_y_m2 = 90e-6;
  p.r_theta_rad2 = 2e-5;
  const std::vector<ReplayInput> inputs{in};
  const ProcessNoiseRate q = equivalent_process_noise_rate(p, inputs);
  const double rate = 300.0 / span_s;
  expect_rel(rate, odometry_rate_hz(inputs), 1e-12);
  expect_rel(rate, q.odometry_rate_hz, 1e-12);
  expect_rel(40e-6 * rate, q.x_m2_per_s, 1e-12);
  expect_rel(90e-6 * rate, q.y_m2_per_s, 1e-12);
  expect_rel(2e-5 * rate, q.theta_rad2_per_s, 1e-12);
  const results::RosExportInput ros = results::ros_input_from_rq(40.0, 90.0, 2e-5, 3600.0, 3600.0, rate);
  expect_rel(ros.process_var_x_m2_per_s, q.x_m2_per_s, 1e-12);
  expect_rel(ros.process_var_yaw_rad2_per_s, q.theta_rad2_per_s, 1e-12);
}

TEST(ProcessNoiseRate, SeveralTracksArePooledByTime) {
  const double dt_a = 0.02, dt_b = 0.1;  // 50 Hz and 10 Hz
  const int n_a = 301, n_b = 101;
  const std::vector<ReplayInput> inputs{straight_line("a", 0.0, 0.01, 0.01, n_a, dt_a),
                                        straight_line("b", 1.2, 0.05, 0.05, n_b, dt_b, 0.97, 10)};
  filters::NoiseParams p;
  p.model = filters::NoiseModel::alpha;
  p.a1 = 0.08;
  const ProcessNoiseRate q = equivalent_process_noise_rate(p, inputs);
  const Eigen::Vector3d Ra = straight_R(std::pow(p.a1 * 0.01, 2), 0.01, 0.0);
  const Eigen::Vector3d Rb = straight_R(std::pow(p.a1 * 0.05, 2), 0.05, 1.2);
  const double T = (n_a - 1) * dt_a + (n_b - 1) * dt_b;
  const Eigen::Vector3d expected = ((n_a - 1) * Ra + (n_b - 1) * Rb) / T;
  expect_rel(expected(0), q.x_m2_per_s);
  expect_rel(expected(1), q.y_m2_per_s);
  expect_rel(expected(2), q.theta_rad2_per_s);
  EXPECT_EQ(q.steps, (n_a - 1) + (n_b - 1));
  expect_rel(((n_a - 1) + (n_b - 1)) / T, q.odometry_rate_hz, 1e-12);
}

TEST(ProcessNoiseRate, BadInputsAreRejected) {
  filters::NoiseParams p;
  p.model = filters::NoiseModel::alpha;
  p.a1 = 0.1;
  EXPECT_THROW(equivalent_process_noise_rate(p, std::span<const ReplayInput>{}), std::invalid_argument);
  EXPECT_THROW(odometry_rate_hz(std::span<const ReplayInput>{}), std::invalid_argument);

  const ReplayInput one = straight_line("short", 0.0, 0.01, 0.01, 1, 0.02);
  try {
    odometry_rate_hz(std::span(&one, 1));
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'short'"), std::string::npos) << e.what();
  }

  const ReplayInput ok = straight_line("ok", 0.0, 0.01, 0.01, 100, 0.02);
  filters::NoiseParams bad = p;
  bad.a1 = -1.0;
  EXPECT_THROW(equivalent_process_noise_rate(bad, std::span(&ok, 1)), std::invalid_argument);

  // A fix that is not a number makes the filter non-finite: named, not averaged.
  ReplayInput nan_fix = ok;
  nan_fix.fixes[0](0) = std::nan("");
  try {
    equivalent_process_noise_rate(p, std::span(&nan_fix, 1));
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("track 'ok': the filter diverges"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace odotune::objectives

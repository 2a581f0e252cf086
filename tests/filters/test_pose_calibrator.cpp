// The online pose-domain calibrator (odotune/filters/pose_calibrator.h): its
// Jacobians against finite differences, a robot standing still, convergence
// from a known start and from fixes alone, a radius step followed by the
// memory pair, outlier fixes, and refused input.
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/core/planar_motion.h>
#include <odotune/filters/memory_pair.h>
#include <odotune/filters/pose_calibrator.h>

namespace odotune::filters {
namespace {

TEST(PoseCalibrator, JacobiansMatchFiniteDifferences) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    PcState s;
    s << 5 * U(rng), 5 * U(rng), 4 * U(rng), 0.3 + 0.02 * U(rng), 0.3 + 0.02 * U(rng), 0.6 + 0.05 * U(rng);
    const double al = 0.3 * U(rng), ar = 0.3 * U(rng);
    const PcPrediction p = pose_calibrator_predict(s, al, ar);
    const double h = 1e-6;
    for (int j = 0; j < kPcDim; ++j) {
      PcState sp = s, sm = s;
      sp(j) += h;
      sm(j) -= h;
      const PcState num =
          (pose_calibrator_predict(sp, al, ar).next - pose_calibrator_predict(sm, al, ar).next) / (2 * h);
      for (int i = 0; i < kPcDim; ++i) EXPECT_NEAR(p.F(i, j), num(i), 1e-7) << i << "," << j;
    }
    // G = ∂next/∂(l, r) at fixed geometry: l = R_L·Δφ_L, so ∂/∂Δφ_L = R_L·G(:, 0).
    const PcState nl =
        (pose_calibrator_predict(s, al + h, ar).next - pose_calibrator_predict(s, al - h, ar).next) / (2 * h);
    const PcState nr =
        (pose_calibrator_predict(s, al, ar + h).next - pose_calibrator_predict(s, al, ar - h).next) / (2 * h);
    for (int i = 0; i < kPcDim; ++i) {
      EXPECT_NEAR(p.G(i, 0) * s(kPcRadiusLeft), nl(i), 1e-7) << i;
      EXPECT_NEAR(p.G(i, 1) * s(kPcRadiusRight), nr(i), 1e-7) << i;
    }
  }
}

// A simulated drive: straights and arcs both ways at `speed` [m/s], 50 Hz
// encoders with wheel noise, fixes every 1/fix_hz s with sd fix_sd.
struct Drive {
  std::vector<PoseCalibSample> samples;
  std::vector<double> t_s;
  PlanarPose start{1.0, -2.0, 0.4};
};

struct Truth {
  double r_left = 0.300, r_right = 0.303, base = 0.62;
};

Drive drive(double duration_s, double speed, double fix_hz, double fix_sd, std::uint64_t seed,
            const std::function<Truth(double)>& truth_at) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> N(0.0, 1.0);
  Drive d;
  const double dt = 0.02;
  double x = d.start.x_m, y = d.start.y_m, th = d.start.theta_rad, next_fix = 1.0 / fix_hz;
  for (double t = dt; t <= duration_s + 1e-9; t += dt) {
    const Truth g = truth_at(t);
    const double phase = std::fmod(t, 40.0);
    const double w = phase < 10.0 ? 0.0 : phase < 20.0 ? 0.4 : phase < 30.0 ? 0.0 : -0.3;
    const double v = speed * (phase < 1.0 ? 0.5 : 1.0);
    const double l = (v - 0.5 * w * g.base) * dt, r = (v + 0.5 * w * g.base) * dt;
    // The wheels' angles from the true radii; the ground rolls with noise.
    const double lr = l + std::sqrt(1e-6 * std::abs(l)) * N(rng),
                 rr = r + std::sqrt(1e-6 * std::abs(r)) * N(rng);
    core::midpoint_advance(&x, &y, &th, lr, rr, g.base);
    PoseCalibSample s{dt, l / g.r_left, r / g.r_right};
    if (t + 1e-9 >= next_fix) {
      s.has_fix = true;
      s.fix_x_m = x + fix_sd * N(rng);
      s.fix_y_m = y + fix_sd * N(rng);
      s.fix_var_x_m2 = s.fix_var_y_m2 = fix_sd * fix_sd;
      next_fix += 1.0 / fix_hz;
    }
    d.samples.push_back(s);
    d.t_s.push_back(t);
  }
  return d;
}

PoseCalibratorParams nominal_params() {
  PoseCalibratorParams p;
  p.initial = {0.30 * 1.02, 0.30 * 0.985, 0.60};  // 2 %, −1.5 % and −3 % off the truth's
  return p;
}

double rel(double est, double truth) { return std::abs(est - truth) / truth; }

TEST(PoseCalibrator, StandingStillLearnsNothingAndStaysFinite) {
  PoseCalibrator f(nominal_params());
  f.start_at({2.0, 3.0, 0.5}, 0.01, 0.01);
  for (int k = 0; k < 600; ++k) {
    PoseCalibSample s{0.1, 0.0, 0.0};
    s.has_fix = k % 10 == 0;
    s.fix_x_m = 2.0, s.fix_y_m = 3.0, s.fix_var_x_m2 = s.fix_var_y_m2 = 0.0036;
    f.step(s);
  }
  const CalibEstimate& e = f.estimate();
  EXPECT_EQ(e.params.wheel_radius_left_m, nominal_params().initial.wheel_radius_left_m);
  EXPECT_EQ(e.params.wheel_base_m, nominal_params().initial.wheel_base_m);
  EXPECT_NEAR(f.pose().x_m, 2.0, 1e-3);
  EXPECT_NEAR(f.pose().y_m, 3.0, 1e-3);
  // No information, and the fading stops at the prior.
  EXPECT_LE(e.sd_radius_left_m, 0.02 * e.params.wheel_radius_left_m * (1 + 1e-12));
  EXPECT_GT(e.sd_radius_left_m, 0.0);
}

TEST(PoseCalibrator, ConvergesFromAKnownStartAndFromFixesAlone) {
  for (bool known : {true, false}) {
    for (const auto& [hz, sd] : {std::pair{1.0, 0.06}, std::pair{10.0, 0.005}, std::pair{0.5, 1.0}}) {
      const double duration = sd > 0.5 ? 1800.0 : 400.0;
      const Drive d = drive(duration, 1.0, hz, sd, 5, [](double) { return Truth{}; });
      PoseCalibrator f(nominal_params());
      if (known) f.start_at(d.start, 0.01, 0.01);
      for (const auto& s : d.samples) f.step(s);
      SCOPED_TRACE(::testing::Message() << (known ? "known" : "fixes") << " start, " << hz << " Hz, sd " << sd);
      EXPECT_TRUE(f.pose_known());
      const Truth g;
      const CalibEstimate& e = f.estimate();
      // GPS-grade fixes (1 m) pin the radii less tightly than 60 mm ones.
      const double tol = sd > 0.5 ? 0.01 : 0.005;
      EXPECT_LT(rel(e.params.wheel_radius_left_m, g.r_left), tol);
      EXPECT_LT(rel(e.params.wheel_radius_right_m, g.r_right), tol);
      EXPECT_LT(rel(e.params.wheel_base_m, g.base), 2 * tol);
      EXPECT_EQ(f.reacquisitions(), 0);
    }
  }
}

TEST(PoseCalibrator, FixesThatPlacedThePoseAlsoInformTheGeometry) {
  // A short drive: the acquisition's fixes are a good share of all of them.
  const Drive d = drive(30.0, 0.5, 1.0, 0.06, 7, [](double) { return Truth{}; });
  PoseCalibrator f(nominal_params());
  long fixes = 0, acquired_at = -1;
  for (const auto& s : d.samples) {
    fixes += s.has_fix ? 1 : 0;
    f.step(s);
    if (f.pose_known() && acquired_at < 0) acquired_at = fixes;
  }
  ASSERT_GT(acquired_at, 2);
  // Every fix went through the filter, those of the acquisition too.
  EXPECT_EQ(f.fixes_applied() + f.fixes_rejected(), fixes);
  // The replay starts where the drive did: the end pose matches the truth's
  // dead reckoning as well as a known start's does.
  PoseCalibrator known(nominal_params());
  known.start_at(d.start, 0.06, 0.1);
  for (const auto& s : d.samples) known.step(s);
  EXPECT_NEAR(f.pose().x_m, known.pose().x_m, 0.05);
  EXPECT_NEAR(f.pose().y_m, known.pose().y_m, 0.05);
  EXPECT_LT(std::abs(f.estimate().params.wheel_base_m - known.estimate().params.wheel_base_m),
            0.5 * std::abs(nominal_params().initial.wheel_base_m - known.estimate().params.wheel_base_m));
}

TEST(PoseCalibrator, ALongWaitForTheFixesToSpreadStartsTheAcquisitionOver) {
  // Standing still with fixes for longer than an acquisition keeps samples:
  // it starts over, and the fixes from before place nothing.
  const Drive d = drive(30.0, 0.5, 1.0, 0.06, 7, [](double) { return Truth{}; });
  PoseCalibrator f(nominal_params());
  PoseCalibSample still{0.01, 0.0, 0.0};
  still.has_fix = true;
  still.fix_x_m = d.start.x_m, still.fix_y_m = d.start.y_m;
  still.fix_var_x_m2 = still.fix_var_y_m2 = 0.0036;
  const long standing = 200001;
  for (long k = 0; k < standing; ++k) f.step(still);
  EXPECT_FALSE(f.pose_known());
  long fixes = 0;
  for (const auto& s : d.samples) {
    fixes += s.has_fix ? 1 : 0;
    f.step(s);
  }
  ASSERT_TRUE(f.pose_known());
  // The drive's fixes and the one standing fix since the acquisition restarted.
  EXPECT_EQ(f.fixes_applied() + f.fixes_rejected(), fixes + (standing - 200000));
  EXPECT_TRUE(std::isfinite(f.pose().x_m));
}

TEST(PoseCalibrator, MemoryPairFollowsARadiusStep) {
  const auto truth = [](double t) {
    Truth g;
    if (t >= 300.0) g.r_left *= 0.985, g.r_right *= 0.99;
    return g;
  };
  const Drive d = drive(600.0, 1.0, 1.0, 0.06, 9, truth);
  const PoseCalibratorParams p = nominal_params();
  MemoryPair<PoseCalibrator, DistanceMemoryParams> pair(PoseCalibrator(p), p.memory, MemoryPairParams{});
  pair.apply([&](PoseCalibrator& f) { f.start_at(d.start, 0.01, 0.01); });
  double settled = -1.0;
  for (std::size_t i = 0; i < d.samples.size(); ++i) {
    const CalibEstimate& e = pair.step(d.samples[i]);
    const Truth g = truth(d.t_s[i]);
    const bool in = rel(e.params.wheel_radius_left_m, g.r_left) < 0.005 &&
                    rel(e.params.wheel_radius_right_m, g.r_right) < 0.005;
    if (d.t_s[i] >= 300.0) {
      if (!in)
        settled = -1.0;
      else if (settled < 0.0)
        settled = d.t_s[i];
    }
  }
  EXPECT_GE(pair.changes(), 1);
  ASSERT_GT(settled, 0.0);
  EXPECT_LT(settled - 300.0, 60.0);
}

TEST(PoseCalibrator, OutlierFixIsRejectedAndALostPoseReacquired) {
  const Drive d = drive(200.0, 1.0, 1.0, 0.06, 11, [](double) { return Truth{}; });
  PoseCalibrator f(nominal_params());
  f.start_at(d.start, 0.01, 0.01);
  std::size_t i = 0;
  for (; d.t_s[i] < 100.0; ++i) f.step(d.samples[i]);
  const CalibEstimate before = f.estimate();
  for (; !d.samples[i].has_fix; ++i) f.step(d.samples[i]);
  PoseCalibSample jump = d.samples[i++];
  jump.fix_x_m += 50.0;
  f.step(jump);
  EXPECT_EQ(f.fixes_rejected(), 1);
  EXPECT_NEAR(f.estimate().params.wheel_radius_left_m, before.params.wheel_radius_left_m, 1e-4);
  // The fixes move for good (a new frame): after max_rejected_fixes the pose follows.
  for (; i < d.samples.size(); ++i) {
    PoseCalibSample s = d.samples[i];
    s.fix_x_m += 50.0;
    f.step(s);
  }
  EXPECT_EQ(f.reacquisitions(), 1);
  EXPECT_NEAR(f.pose().x_m, d.samples.back().fix_x_m + 50.0, 1.0);
}

TEST(PoseCalibrator, RefusesBadParamsAndSamples) {
  PoseCalibratorParams p = nominal_params();
  p.initial.wheel_base_m = 0.0;
  std::string why;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("initial.wheel_base_m"), std::string::npos) << why;
  EXPECT_THROW(PoseCalibrator{p}, std::invalid_argument);
  PoseCalibrator f(nominal_params());
  PoseCalibSample s{0.1, 0.1, 0.1};
  s.has_fix = true;
  s.fix_var_x_m2 = 0.0;
  s.fix_var_y_m2 = 1.0;
  EXPECT_THROW(f.step(s), std::invalid_argument);
  s = PoseCalibSample{-0.1, 0.0, 0.0};
  EXPECT_THROW(f.step(s), std::invalid_argument);
}

}  // namespace
}  // namespace odotune::filters

// The particle-filter calibrator's settings as a tuning problem
// (odotune/calibration/calibration_objective.h): the space, applying a point,
// the score's terms on hand-built results, and the objective on a short
// simulated wheelchair drive.
#include <odotune/calibration/calibration_objective.h>

#include <omp.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/calibration/calibrated_odometry_errors.h>
#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_run.h>

#include "diagnose/sim_track.h"

namespace odotune::calibration {
namespace {

// ---------------------------------------------------------------------------
// The space.

TEST(CalibrationSpace, NamesUnitsBoundsAndScalesAsDocumented) {
  const objectives::BoxSpace s = calibration_space();
  ASSERT_EQ(s.dim(), 5u);
  const char* names[] = {"neff_fraction", "max_weight_ratio", "alpha", "dispersion_per_particle_mm",
                         "random_walk_sigma_mm"};
  const char* units[] = {"-", "-", "m/(m/s)", "mm", "mm"};
  const double lower[] = {0.05, 1.0, 1e-6, 1e-3, 1e-3};
  const double upper[] = {1.0, 1000.0, 1e-1, 1.0, 5.0};
  const bool log_scale[] = {false, true, true, true, true};
  for (std::size_t i = 0; i < 5; ++i) {
    const objectives::ParamSpec& p = s.params()[i];
    EXPECT_EQ(p.name, names[i]);
    EXPECT_EQ(p.unit, units[i]) << p.name;
    EXPECT_DOUBLE_EQ(p.lower, lower[i]) << p.name;
    EXPECT_DOUBLE_EQ(p.upper, upper[i]) << p.name;
    EXPECT_EQ(p.log_scale, log_scale[i]) << p.name;
    EXPECT_FALSE(p.meaning.empty()) << p.name;
  }
  // The optimiser's box: log10 of the bounds for log-scaled parameters.
  const auto [lo, hi] = s.box();
  EXPECT_DOUBLE_EQ(lo[0], 0.05);
  EXPECT_DOUBLE_EQ(hi[0], 1.0);
  EXPECT_NEAR(lo[1], 0.0, 1e-15);
  EXPECT_NEAR(hi[1], 3.0, 1e-15);
  EXPECT_NEAR(lo[2], -6.0, 1e-15);
  EXPECT_NEAR(hi[2], -1.0, 1e-15);
  EXPECT_NEAR(lo[3], -3.0, 1e-15);
  EXPECT_NEAR(hi[3], 0.0, 1e-15);
  EXPECT_NEAR(lo[4], -3.0, 1e-15);
  EXPECT_NEAR(hi[4], std::log10(5.0), 1e-15);
}

TEST(CalibrationSpace, BoxAndPhysicalRoundTrip) {
  const objectives::BoxSpace s = calibration_space();
  const std::vector<double> physical = {0.3, 25.0, 3e-4, 0.02, 0.7};
  const std::vector<double> box = s.to_box(physical);
  EXPECT_DOUBLE_EQ(box[0], 0.3);  // linear
  EXPECT_NEAR(box[1], std::log10(25.0), 1e-15);
  const std::vector<double> back = s.to_physical(box);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_NEAR(back[i], physical[i], 1e-12 * physical[i]) << i;
  // Box coordinates outside the box are clamped onto it.
  const auto [lo, hi] = s.box();
  std::vector<double> outside = hi;
  for (auto& v : outside) v += 1.0;
  const std::vector<double> clamped = s.to_physical(outside);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_NEAR(clamped[i], s.params()[i].upper, 1e-12) << i;
  EXPECT_THROW(s.to_physical(std::vector<double>(4, 0.0)), std::invalid_argument);
}

TEST(CalibrationSpace, ThePapersDefaultsLieInsideTheBounds) {
  const objectives::BoxSpace s = calibration_space();
  for (const auto& p : {filters::PfCalibratorParams{}, filters::PfCalibratorParams::adaptive_defaults()}) {
    const std::vector<double> v = calibration_params_of(p);
    ASSERT_EQ(v.size(), 5u);
    // N_th = 0.5·N, max-weight ratio 10, α = 1e-4, 0.01 mm per particle, σ = 0.5 mm.
    EXPECT_DOUBLE_EQ(v[0], 0.5);
    EXPECT_DOUBLE_EQ(v[1], 10.0);
    EXPECT_DOUBLE_EQ(v[2], 1e-4);
    EXPECT_NEAR(v[3], 0.01, 1e-15);
    EXPECT_NEAR(v[4], 0.5, 1e-15);
    for (std::size_t i = 0; i < 5; ++i) {
      EXPECT_GT(v[i], s.params()[i].lower) << s.params()[i].name;
      EXPECT_LT(v[i], s.params()[i].upper) << s.params()[i].name;
    }
  }
}

TEST(ApplyCalibrationParams, SetsExactlyTheFiveFieldsInSi) {
  filters::PfCalibratorParams base;
  base.wheel_radius_left_m = {0.1, 0.2};
  base.wheel_radius_right_m = {0.11, 0.21};
  base.wheel_base_m = {0.4, 0.5};
  base.particles = 1234;
  base.v_perturbation_m_s = 0.02;
  base.w_perturbation_rad_s = 0.03;
  base.resampler = filters::Resampler::residual;
  base.policy = filters::ResamplePolicy::max_weight;
  base.adaptive = true;
  base.min_random_walk_sigma_m = 1e-6;
  base.min_particles = 300;
  base.max_particles = 9000;
  base.seed = 77;
  base.threads = 3;
  const std::vector<double> v = {0.25, 40.0, 2e-3, 0.05, 1.5};
  const filters::PfCalibratorParams p = apply_calibration_params(base, v);
  EXPECT_DOUBLE_EQ(p.neff_fraction, 0.25);
  EXPECT_DOUBLE_EQ(p.max_weight_ratio, 40.0);
  EXPECT_DOUBLE_EQ(p.alpha, 2e-3);
  EXPECT_NEAR(p.dispersion_per_particle_m, 0.05e-3, 1e-18);  // mm → m
  EXPECT_NEAR(p.random_walk_sigma_m, 1.5e-3, 1e-18);         // mm → m
  // Everything else is the base's.
  EXPECT_EQ(p.wheel_radius_left_m.lo, 0.1);
  EXPECT_EQ(p.wheel_radius_left_m.hi, 0.2);
  EXPECT_EQ(p.wheel_radius_right_m.lo, 0.11);
  EXPECT_EQ(p.wheel_radius_right_m.hi, 0.21);
  EXPECT_EQ(p.wheel_base_m.lo, 0.4);
  EXPECT_EQ(p.wheel_base_m.hi, 0.5);
  EXPECT_EQ(p.particles, 1234);
  EXPECT_EQ(p.v_perturbation_m_s, 0.02);
  EXPECT_EQ(p.w_perturbation_rad_s, 0.03);
  EXPECT_EQ(p.resampler, filters::Resampler::residual);
  EXPECT_EQ(p.policy, filters::ResamplePolicy::max_weight);
  EXPECT_TRUE(p.adaptive);
  EXPECT_EQ(p.min_random_walk_sigma_m, 1e-6);
  EXPECT_EQ(p.min_particles, 300);
  EXPECT_EQ(p.max_particles, 9000);
  EXPECT_EQ(p.seed, 77u);
  EXPECT_EQ(p.threads, 3);
  // calibration_params_of is its inverse.
  const std::vector<double> back = calibration_params_of(p);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_NEAR(back[i], v[i], 1e-12 * v[i]) << i;
  EXPECT_THROW(apply_calibration_params(base, std::vector<double>(6, 1.0)), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// The score, on hand-built results (file comment of calibration_objective.h:
// w_radius·e_R/0.5 % + w_convergence·c + w_pose·RMSE/(0.5 % of the path) + w_cost·N̄/8000).

CalibrationInput input_lasting(double duration_s, const std::string& name = "t") {
  CalibrationInput in;
  in.track_name = name;
  in.nominal = {0.32, 0.32, 0.65};
  in.t = {0.0, duration_s};
  // A straight 40 m ground-truth path: the pose term's scale is 0.5 % of it, 0.2 m.
  in.gt_x = {0.0, 40.0};
  in.gt_y = {0.0, 0.0};
  in.gt_theta = {0.0, 0.0};
  in.has_gt = true;
  return in;
}

filters::OdometryParams truth() { return {0.3168, 0.32384, 0.65}; }

// A perfect calibration of one track: exact radii at once, pose error 0.
TrackCalibrationScore perfect_track() {
  TrackCalibrationScore s;
  s.final_params = truth();
  s.truth_final = truth();
  s.convergence_time_s = 0.0;
  s.pose_rmse_m = 0.0;
  return s;
}

TEST(CalibrationScore, PerfectCalibrationScoresOnlyTheCostTerm) {
  const CalibrationInput in = input_lasting(100.0);
  CalibrationResult r;
  r.tracks = {perfect_track()};
  r.mean_particles = 2000.0;
  CalibrationScoreWeights w;  // radius 1, convergence 1, pose 1, cost 0.25
  EXPECT_DOUBLE_EQ(calibration_score(r, {&in}, w), 0.25 * 2000.0 / 8000.0);
  w.cost = 0.0;
  EXPECT_DOUBLE_EQ(calibration_score(r, {&in}, w), 0.0);
}

TEST(CalibrationScore, EachTermAsDocumented) {
  const CalibrationInput in = input_lasting(100.0);
  CalibrationScoreWeights w;
  w.cost = 0.0;

  // Radius: mean relative error of both radii over the 0.5 % band.
  CalibrationResult r;
  r.tracks = {perfect_track()};
  r.tracks[0].final_params.wheel_radius_left_m = truth().wheel_radius_left_m * 1.005;  // 0.5 %
  EXPECT_NEAR(calibration_score(r, {&in}, w), 0.5, 1e-12);                             // mean of 1 and 0
  r.tracks[0].final_params.wheel_radius_right_m = truth().wheel_radius_right_m * (1 - 0.01);
  EXPECT_NEAR(calibration_score(r, {&in}, w), 0.5 * (1.0 + 2.0), 1e-12);
  w.radius = 2.0;
  EXPECT_NEAR(calibration_score(r, {&in}, w), 3.0, 1e-12);
  w.radius = 1.0;

  // Convergence: time over the track's duration.
  r.tracks = {perfect_track()};
  r.tracks[0].convergence_time_s = 25.0;
  EXPECT_NEAR(calibration_score(r, {&in}, w), 0.25, 1e-12);
  // Never converged adds w.convergence.
  r.tracks[0].convergence_time_s.reset();
  w.convergence = 3.0;
  EXPECT_NEAR(calibration_score(r, {&in}, w), 3.0, 1e-12);
  w.convergence = 1.0;

  // Pose: calibrated RMSE over 0.5 % of the 40 m path (0.2 m).
  r.tracks = {perfect_track()};
  r.tracks[0].pose_rmse_m = 0.1;
  EXPECT_NEAR(calibration_score(r, {&in}, w), 0.5, 1e-12);
  // A non-finite pose RMSE (no ground truth) adds nothing.
  r.tracks[0].pose_rmse_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NEAR(calibration_score(r, {&in}, w), 0.0, 1e-12);
}

TEST(CalibrationScore, TrackWithoutTruthScoresOnlyPoseAndCost) {
  const CalibrationInput in = input_lasting(100.0);
  CalibrationResult r;
  TrackCalibrationScore s;
  s.final_params = {0.40, 0.20, 0.9};  // far off, but there is no truth to tell
  s.pose_rmse_m = 0.3;                 // never converged: no truth either
  r.tracks = {s};
  r.mean_particles = 4000.0;
  const CalibrationScoreWeights w;
  EXPECT_NEAR(calibration_score(r, {&in}, w), 0.3 / 0.2 + 0.25 * 0.5, 1e-12);
}

TEST(CalibrationScore, IsTheMeanOverTracksAndChecksSizes) {
  const CalibrationInput a = input_lasting(100.0, "a"), b = input_lasting(50.0, "b");
  CalibrationResult r;
  r.tracks = {perfect_track(), perfect_track()};
  r.tracks[1].convergence_time_s = 25.0;  // half of b's 50 s
  CalibrationScoreWeights w;
  w.cost = 0.0;
  EXPECT_NEAR(calibration_score(r, {&a, &b}, w), 0.25, 1e-12);
  EXPECT_THROW(calibration_score(r, {&a}, w), std::invalid_argument);
}

TEST(CalibrationScoreWeights, RejectsNegativeAndNonFiniteWeightsByName) {
  std::string why;
  EXPECT_TRUE(CalibrationScoreWeights{}.IsValid(&why));
  CalibrationScoreWeights w;
  w.pose = -1.0;
  EXPECT_FALSE(w.IsValid(&why));
  EXPECT_NE(why.find("pose"), std::string::npos) << why;
  w = {};
  w.cost = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(w.IsValid(&why));
  EXPECT_NE(why.find("cost"), std::string::npos) << why;
}

// ---------------------------------------------------------------------------
// The objective on a short simulated wheelchair drive: R = 0.32 m, D = 0.65 m,
// 8800 counts/rev, encoders 100 Hz, external velocities 10 Hz σ 0.02, ground
// truth 100 Hz; true radii 0.99 / 1.012 × nominal.

tracks::Track wheelchair_track() {
  testing_support::SimTrackOptions o;
  o.duration_s = 30.0;
  o.wheel_radius_left_m = o.wheel_radius_right_m = 0.32;
  o.wheel_base_m = 0.65;
  o.ticks_per_rev = 8800;
  o.odo_rate_hz = 100.0;
  o.gyro_rate_hz = 0.0;
  o.gt_rate_hz = 100.0;
  o.effects = {"radius_error:scale_l=0.99,scale_r=1.012"};
  o.seed = 5;
  sim::Scenario sc = testing_support::sim_scenario(o);
  sc.name = "wheelchair_short";
  sc.sensors.ext_velocity.enabled = true;
  sc.sensors.ext_velocity.rate_hz = 10.0;
  sc.sensors.ext_velocity.sigma_v_m_s = 0.02;
  sc.sensors.ext_velocity.sigma_w_rad_s = 0.02;
  return sim::simulate(sc);
}

const CalibrationInput& wheelchair_input() {
  static const CalibrationInput in = build_calibration_input(wheelchair_track(), {});
  return in;
}

filters::PfCalibratorParams small_base() {
  filters::PfCalibratorParams p;  // the wheelchair's ranges
  p.particles = 600;
  p.min_particles = 300;
  p.max_particles = 3000;
  p.seed = 11;
  return p;
}

TEST(CalibrationObjective, TheSimulatedTrackHasWhatTheObjectiveNeeds) {
  const CalibrationInput& in = wheelchair_input();
  ASSERT_TRUE(in.has_gt);
  ASSERT_TRUE(in.truth.has_value());
  EXPECT_NEAR(in.truth->at(10.0).wheel_radius_left_m, 0.32 * 0.99, 1e-12);
  EXPECT_NEAR(in.truth->at(10.0).wheel_radius_right_m, 0.32 * 1.012, 1e-12);
  EXPECT_GT(in.samples.size(), 250u);  // ≥ 30 s at 10 Hz
}

TEST(CalibrationObjective, FitnessIsDeterministicAcrossCallsAndThreads) {
  const CalibrationObjective obj({&wheelchair_input()}, small_base(), /*adaptive=*/true);
  const objectives::BoxSpace& s = obj.space();
  const std::vector<double> x = s.to_box(std::vector<double>{0.4, 20.0, 3e-4, 0.02, 0.3});
  const double f1 = obj.fitness(x);
  const double f2 = obj.fitness(x);
  ASSERT_TRUE(std::isfinite(f1));
  EXPECT_LT(f1, kCalibrationPenalty);
  EXPECT_EQ(f1, f2);
  double from_thread[2] = {0.0, 0.0};
  int team = 0;
#pragma omp parallel num_threads(2)
  {
    const int k = omp_get_thread_num();
    if (k == 0) team = omp_get_num_threads();
    if (k < 2) from_thread[k] = obj.fitness(x);
  }
  ASSERT_EQ(team, 2);
  EXPECT_EQ(from_thread[0], f1);
  EXPECT_EQ(from_thread[1], f1);
  EXPECT_EQ(obj.failures(), 0);
  EXPECT_GE(obj.evaluations(), 3);
  // The run behind the score is the one run_calibration gives.
  const CalibrationResult r = obj.run(x);
  EXPECT_EQ(calibration_score(r, {&wheelchair_input()}, {}), f1);
}

TEST(CalibrationObjective, ThePapersSettingsScoreBetterThanAnAbsurdRandomWalk) {
  const CalibrationObjective obj({&wheelchair_input()}, small_base(), /*adaptive=*/false);
  const objectives::BoxSpace& s = obj.space();
  std::vector<double> paper = calibration_params_of(filters::PfCalibratorParams{});
  std::vector<double> absurd = paper;
  absurd[4] = s.params()[4].upper;  // random-walk σ 5 mm per iteration
  const double f_paper = obj.fitness(s.to_box(paper));
  const double f_absurd = obj.fitness(s.to_box(absurd));
  ASSERT_TRUE(std::isfinite(f_paper));
  ASSERT_TRUE(std::isfinite(f_absurd));
  EXPECT_LT(f_paper, f_absurd);
  // The absurd walk also leaves the final radii further from the truth.
  const auto final_error = [&](const std::vector<double>& v) {
    const CalibrationResult r = obj.run(s.to_box(v));
    const TrackCalibrationScore& t = r.tracks.at(0);
    return std::abs(t.final_params.wheel_radius_left_m - t.truth_final->wheel_radius_left_m) +
           std::abs(t.final_params.wheel_radius_right_m - t.truth_final->wheel_radius_right_m);
  };
  EXPECT_LT(final_error(paper), final_error(absurd));
  EXPECT_EQ(obj.failures(), 0);
}

TEST(CalibrationObjective, InvalidPointsArePenalisedAndCountedNeverThrown) {
  const CalibrationObjective obj({&wheelchair_input()}, small_base(), /*adaptive=*/false);
  const std::vector<double> nan_point(5, std::numeric_limits<double>::quiet_NaN());
  const std::vector<double> wrong_dimension(3, 0.0);
  double f_nan = 0.0, f_dim = 0.0;
  EXPECT_NO_THROW(f_nan = obj.fitness(nan_point));
  EXPECT_NO_THROW(f_dim = obj.fitness(wrong_dimension));
  EXPECT_EQ(f_nan, kCalibrationPenalty);
  EXPECT_EQ(f_dim, kCalibrationPenalty);
  EXPECT_EQ(obj.failures(), 2);
  EXPECT_EQ(obj.evaluations(), 2);
}

TEST(CalibrationObjective, RefusesNoTracksAndInvalidBaseAtConstruction) {
  EXPECT_THROW(CalibrationObjective({}, small_base(), false), std::invalid_argument);
  filters::PfCalibratorParams bad = small_base();
  bad.particles = 0;
  EXPECT_THROW(CalibrationObjective({&wheelchair_input()}, bad, false), std::invalid_argument);
  CalibrationScoreWeights w;
  w.radius = -1.0;
  EXPECT_THROW(CalibrationObjective({&wheelchair_input()}, small_base(), false, w), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// The MAE/MAXE of the calibrated odometry (calibrated_odometry_errors.h).

TEST(CalibratedOdometryErrors, RmseMatchesCalibrationRunAndMetricsAreOrdered) {
  const CalibrationInput& in = wheelchair_input();
  CalibrationOptions o;
  o.method = CalibrationMethod::pf;
  o.pf = small_base();
  const CalibrationResult r = run_calibration({&in}, o);
  const filters::OdometryParams before = filters::PfCalibrator(effective_pf_params(o)).estimate().params;
  const objectives::ErrorMetrics e = calibrated_odometry_errors(in, r.trace, 0, before);
  EXPECT_GT(e.samples, 1000);
  EXPECT_NEAR(e.rmse_m, r.tracks[0].pose_rmse_m, 1e-9 * r.tracks[0].pose_rmse_m);
  EXPECT_LE(e.mae_m, e.rmse_m);
  EXPECT_LE(e.rmse_m, e.maxe_m);
  // Fixed parameters: the same as score_fixed_params; the truth beats the nominal.
  const filters::OdometryParams truth_now = in.truth->at(0.0);
  const objectives::ErrorMetrics fixed_truth = fixed_odometry_errors(in, truth_now);
  const objectives::ErrorMetrics fixed_nominal = fixed_odometry_errors(in, in.nominal);
  EXPECT_NEAR(fixed_nominal.rmse_m, score_fixed_params(in, in.nominal).pose_rmse_m, 1e-9);
  EXPECT_LT(fixed_truth.maxe_m, fixed_nominal.maxe_m);
  EXPECT_LT(fixed_truth.rmse_m, 0.2 * fixed_nominal.rmse_m);
  // A trace of another track leaves `before` in force throughout.
  EXPECT_NEAR(calibrated_odometry_errors(in, r.trace, 1, in.nominal).rmse_m, fixed_nominal.rmse_m, 1e-12);
}

}  // namespace
}  // namespace odotune::calibration

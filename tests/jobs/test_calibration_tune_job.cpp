// One calibrator tuning run (odotune/jobs/calibration_tune_job.h) on a short
// simulated wheelchair drive, in process: the default calibrator, the
// never-worse-than-the-defaults rule, NLopt starting from the defaults, and
// tracks of different robots refused.
#include <odotune/jobs/calibration_tune_job.h>

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include <odotune/calibration/calibration_objective.h>

#include "diagnose/sim_track.h"

namespace odotune::jobs {
namespace {

using odotune::jobs::CalibrationTuneRequest;
using odotune::objectives::CalibratorModel;

// 20 s of the wheelchair (R = 0.32 m, D = 0.65 m, 8800 counts/rev, encoders
// 100 Hz, v_ext/w_ext 10 Hz σ 0.02, ground truth 100 Hz, radii 0.99 / 1.012).
calibration::CalibrationInput wheelchair(const std::string& name, double radius_m = 0.32) {
  testing_support::SimTrackOptions o;
  o.duration_s = 20.0;
  o.wheel_radius_left_m = o.wheel_radius_right_m = radius_m;
  o.wheel_base_m = 0.65;
  o.ticks_per_rev = 8800;
  o.gyro_rate_hz = 0.0;
  o.effects = {"radius_error:scale_l=0.99,scale_r=1.012"};
  o.seed = 3;
  sim::Scenario sc = testing_support::sim_scenario(o);
  sc.name = name;
  sc.sensors.ext_velocity.enabled = true;
  sc.sensors.ext_velocity.rate_hz = 10.0;
  sc.sensors.ext_velocity.sigma_v_m_s = 0.02;
  sc.sensors.ext_velocity.sigma_w_rad_s = 0.02;
  return calibration::build_calibration_input(sim::simulate(sc), {});
}

const calibration::CalibrationInput& track() {
  static const calibration::CalibrationInput in = wheelchair("chair");
  return in;
}

CalibrationTuneRequest small_request(CalibratorModel model) {
  CalibrationTuneRequest r;
  r.model = model;
  r.pf_particles = 300;
  r.pf_seed = 4;
  r.particles = 1;
  r.iterations = 0;
  return r;
}

TEST(DefaultCalibrator, ThePapersSettingsAroundTheRobotsNominalValues) {
  CalibrationTuneRequest r = small_request(CalibratorModel::adaptive_pf);
  r.resampler = filters::Resampler::multinomial;
  r.policy = filters::ResamplePolicy::every_step;
  const filters::PfCalibratorParams p = odotune::jobs::default_calibrator(r, {0.05, 0.06, 0.3});
  EXPECT_TRUE(p.adaptive);
  EXPECT_EQ(p.particles, 300);
  EXPECT_EQ(p.seed, 4u);
  EXPECT_EQ(p.resampler, filters::Resampler::multinomial);
  EXPECT_EQ(p.policy, filters::ResamplePolicy::every_step);
  // Radii nominal ± 5 %, base ± 15 % (`odotune calibrate`'s defaults).
  EXPECT_NEAR(p.wheel_radius_left_m.lo, 0.0475, 1e-12);
  EXPECT_NEAR(p.wheel_radius_left_m.hi, 0.0525, 1e-12);
  EXPECT_NEAR(p.wheel_radius_right_m.lo, 0.057, 1e-12);
  EXPECT_NEAR(p.wheel_base_m.lo, 0.255, 1e-12);
  EXPECT_NEAR(p.wheel_base_m.hi, 0.345, 1e-12);
  // The tuned settings are the paper's.
  EXPECT_EQ(calibration::calibration_params_of(p),
            calibration::calibration_params_of(filters::PfCalibratorParams::adaptive_defaults()));
  // No particle count given: the paper's counts.
  r.pf_particles.reset();
  EXPECT_EQ(odotune::jobs::default_calibrator(r, {0.32, 0.32, 0.65}).particles, 8000);
  r.model = CalibratorModel::pf;
  EXPECT_EQ(odotune::jobs::default_calibrator(r, {0.32, 0.32, 0.65}).particles, 5000);
  EXPECT_FALSE(odotune::jobs::default_calibrator(r, {0.32, 0.32, 0.65}).adaptive);
}

// With one random PSO point the solver often does worse than the defaults:
// then the defaults are kept, so the tuned score never exceeds the baseline.
TEST(CalibrationTune, TunedIsTheBetterOfTheSolversBestAndTheDefaults) {
  int kept = 0, improved = 0;
  // Seeds until both branches have run (at most 40).
  for (std::uint64_t seed = 1; seed <= 40 && (kept == 0 || improved == 0); ++seed) {
    CalibrationTuneRequest r = small_request(CalibratorModel::pf);
    r.seed = seed;
    const odotune::jobs::CalibrationTuneOutcome o = odotune::jobs::run_calibration_tune({&track()}, r);
    ASSERT_EQ(o.summary.evaluations, 1);
    EXPECT_EQ(o.tuned_score, std::min(o.baseline_score, o.summary.best_fitness)) << seed;
    EXPECT_EQ(o.default_kept, o.baseline_score < o.summary.best_fitness) << seed;
    if (o.default_kept) {
      ++kept;
      EXPECT_EQ(o.params, o.default_params) << seed;
      // The "tuned" run is then the baseline run.
      EXPECT_EQ(o.tuned_mean.rmse_m, o.baseline_mean.rmse_m) << seed;
    } else {
      ++improved;
      EXPECT_NE(o.params, o.default_params) << seed;
    }
    EXPECT_EQ(o.failures, 0) << seed;
  }
  // Both branches ran (else this test would prove half of the rule).
  EXPECT_GT(kept, 0);
  EXPECT_GT(improved, 0);
}

TEST(CalibrationTune, NloptStartsFromTheDefaults) {
  CalibrationTuneRequest r = small_request(CalibratorModel::adaptive_pf);
  r.solver = {odotune::tuner::SolverChoice::Kind::nlopt, "SBPLX"};
  r.evaluations = 4;
  const odotune::jobs::CalibrationTuneOutcome o = odotune::jobs::run_calibration_tune({&track()}, r);
  EXPECT_LE(o.summary.evaluations, 4);
  ASSERT_FALSE(o.summary.log.empty());
  // The first evaluation is the default point: its score is the baseline's.
  EXPECT_EQ(o.summary.log.front().evaluations, 1);
  EXPECT_EQ(o.summary.log.front().best_fitness, o.baseline_score);
  EXPECT_FALSE(o.default_kept);
  EXPECT_LE(o.tuned_score, o.baseline_score);
}

TEST(CalibrationTune, ScoresAndErrorsAreConsistent) {
  const odotune::jobs::CalibrationTuneOutcome o = odotune::jobs::run_calibration_tune(
      {&track()}, small_request(CalibratorModel::adaptive_pf));
  ASSERT_EQ(o.baseline.tracks.size(), 1u);
  ASSERT_EQ(o.tuned.tracks.size(), 1u);
  EXPECT_EQ(o.baseline.tracks[0].track, "chair");
  // The position RMSE is calibration_run's pose RMSE of the same run.
  for (const auto* e : {&o.baseline, &o.tuned}) {
    const auto& t = e->tracks[0];
    EXPECT_NEAR(t.errors.rmse_m, t.calibration.pose_rmse_m, 1e-9 * t.calibration.pose_rmse_m);
    EXPECT_LE(t.errors.mae_m, t.errors.rmse_m);
    EXPECT_LE(t.errors.rmse_m, t.errors.maxe_m);
    EXPECT_GT(e->mean_particles, 0.0);
  }
  EXPECT_EQ(o.baseline_mean.rmse_m, o.baseline.tracks[0].errors.rmse_m);
  EXPECT_EQ(o.param_names.size(), 5u);
  EXPECT_EQ(o.param_names[4], "random_walk_sigma_mm");
  EXPECT_EQ(o.param_units[4], "mm");
}

TEST(CalibrationTune, RefusesTracksOfDifferentRobotsAndBadRequests) {
  const calibration::CalibrationInput other = wheelchair("small", 0.30);
  EXPECT_THROW(odotune::jobs::run_calibration_tune({&track(), &other}, small_request(CalibratorModel::pf)),
               std::invalid_argument);
  EXPECT_THROW(odotune::jobs::run_calibration_tune({}, small_request(CalibratorModel::pf)),
               std::invalid_argument);
  CalibrationTuneRequest bad = small_request(CalibratorModel::pf);
  bad.solver = {odotune::tuner::SolverChoice::Kind::nlopt, "ANNEALING"};
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("ANNEALING"), std::string::npos) << why;
  EXPECT_THROW(odotune::jobs::run_calibration_tune({&track()}, bad), std::invalid_argument);
  bad = small_request(CalibratorModel::pf);
  bad.weights.pose = -1;
  EXPECT_THROW(odotune::jobs::run_calibration_tune({&track()}, bad), std::invalid_argument);
  bad = small_request(CalibratorModel::pf);
  bad.pf_particles = -5;
  EXPECT_FALSE(bad.IsValid(&why));
}

}  // namespace
}  // namespace odotune::jobs

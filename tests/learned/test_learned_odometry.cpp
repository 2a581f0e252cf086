// Learned odometry (odotune/learned/learned_odometry.h), the slip detector
// (slip_detector.h), the fused system with online retraining
// (learned_fusion.h) and the Table 1–3 metrics (odometry_metrics.h), on
// wheelchair-like tracks simulated in memory (calibration_track.h).
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include <odotune/learned/fusion_input.h>
#include <odotune/learned/learned_fusion.h>
#include <odotune/learned/learned_odometry.h>
#include <odotune/learned/odometry_metrics.h>
#include <odotune/learned/odometry_selection.h>
#include <odotune/learned/slip_detector.h>
#include <odotune/sim/slip_episodes.h>

#include "support/calibration_track.h"

namespace odotune::learned {
namespace {

using testing_support::ChairTrackOptions;

// Effects a kinematic model with the nominal geometry lacks: unequal tyres,
// a wider contact base, tyres growing with speed and traction loss when
// accelerating (../shared/specs/physics-effects.md).
const std::vector<std::string> kHiddenEffects = {"radius_error:scale_l=1.012,scale_r=0.991",
                                                 "wheel_base_error:scale=1.02", "speed_radius:c=0.02",
                                                 "longitudinal_slip:k=0.05"};

FusionInput chair_input(double duration_s, std::uint64_t seed,
                        std::vector<std::string> effects = kHiddenEffects) {
  ChairTrackOptions o;
  o.duration_s = duration_s;
  o.seed = seed;
  o.effects = std::move(effects);
  return build_fusion_input(testing_support::chair_track(o));
}

LearnedTrainingOptions quick_training() {
  LearnedTrainingOptions o;
  o.training.max_iterations = 60;
  o.training.seed = 3;
  return o;
}

// The kinematic model misses a few % of V and W; a trained model learns it:
// on the held-out drive it is at least 20 % better in V and W, and better in position.
void expect_beats_kinematics(const FusionInput& test, const LearnedOdometryModel& model) {
  const OdometrySeries learned = run_learned_odometry(test, model);
  const OdometrySeries kin = kinematic_odometry(test);
  const OdometryErrors el = odometry_errors(test, learned.v, learned.w, {}, {}, {});
  const OdometryErrors ek = odometry_errors(test, kin.v, kin.w, {}, {}, {});
  EXPECT_LT(el.v.mae, 0.8 * ek.v.mae);
  EXPECT_LT(el.w.mae, 0.8 * ek.w.mae);
  EXPECT_LT(el.xy.rmse, ek.xy.rmse);
}

TEST(OdometryMetrics, SeriesErrorsMatchTheirDefinitions) {
  // est − truth = (skip step 0) 0.1, −0.2, 0.3; truth 1, 2, 3 (mean 2).
  const std::vector<double> truth = {9, 1, 2, 3}, est = {0, 1.1, 1.8, 3.3}, var = {1, 0.01, 0.04, 0.09};
  const SeriesErrors e = series_errors(est, truth, var);
  EXPECT_EQ(e.samples, 3u);
  EXPECT_NEAR(e.mae, (0.1 + 0.2 + 0.3) / 3, 1e-12);
  EXPECT_NEAR(e.rmse, std::sqrt((0.01 + 0.04 + 0.09) / 3), 1e-12);
  EXPECT_NEAR(e.r2, 1.0 - 0.14 / 2.0, 1e-12);  // Σ(y−ȳ)² = 1 + 0 + 1
  EXPECT_NEAR(e.nees, 1.0, 1e-12);             // each e²/var = 1
  const SeriesErrors no_var = series_errors(est, truth, {});
  EXPECT_TRUE(std::isnan(no_var.nees));
}

TEST(OdometryMetrics, DeadReckoningTheTruthReproducesTheGroundTruthPath) {
  const FusionInput in = chair_input(40, 5, {});
  const OdometryErrors e = odometry_errors(in, in.v_true, in.w_true, {}, {}, {});
  EXPECT_LT(e.v.mae, 1e-9);
  EXPECT_GT(e.xy.r2, 0.999);
  // Euler integration (eq. 3) of exact step-mean velocities drifts only by
  // the discretisation: well under 5 cm over 40 s.
  EXPECT_LT(e.xy.rmse, 0.05);
  const OdometryErrors kin = odometry_errors(in, in.v_kin, in.w_kin, {}, {}, {});
  EXPECT_LT(kin.v.mae, 0.01);  // effect-free: kinematic odometry is right
}

TEST(LearnedOdometry, BeatsTheKinematicModelOnHeldOutDataWithHiddenEffects) {
  const FusionInput train = chair_input(150, 11);
  const FusionInput test = chair_input(80, 12);
  LearnedTrainingSummary summary;
  const LearnedOdometryModel model = train_learned_odometry({&train}, quick_training(), &summary);
  EXPECT_GT(summary.train_windows, 500u);
  EXPECT_GT(summary.validation_windows, 200u);
  EXPECT_TRUE(summary.v.usable);
  EXPECT_TRUE(summary.w.usable);

  expect_beats_kinematics(test, model);
}

// A small cross-validation grid, so the tests stay quick.
SelectionOptions quick_selection() {
  SelectionOptions o;
  o.training.max_iterations = 40;
  o.training.seed = 3;
  o.units = {3};
  o.windows = {10};
  o.weight_decays = {0.0};
  o.features = {LearnedFeatures::both};
  return o;
}

// Correction nets learn what the kinematic model misses and are added to it:
// chosen by cross-validation over two drives and kept, they beat the
// kinematics on a third drive as the paper's nets do.
TEST(LearnedOdometry, CorrectionNetsLearnWhatTheKinematicModelMisses) {
  const FusionInput a = chair_input(100, 11), b = chair_input(100, 13);
  const FusionInput test = chair_input(80, 12);
  SelectionSummary summary;
  const LearnedOdometryModel model = train_correction_odometry({&a, &b}, quick_selection(), &summary);
  EXPECT_EQ(model.target, LearnedTarget::correction);
  EXPECT_EQ(model.features, LearnedFeatures::both);
  EXPECT_EQ(model.v_net.units(), 3);
  EXPECT_TRUE(model.gyro);  // every drive has one: the features read it
  EXPECT_TRUE(summary.gyro);
  EXPECT_EQ(summary.folds, 2);
  ASSERT_EQ(summary.units.size(), 2u);
  EXPECT_EQ(summary.combination, NetCombination::both);
  EXPECT_TRUE(model.v_beats_kinematic);
  EXPECT_TRUE(model.w_beats_kinematic);
  for (const FoldMeasures& f : summary.candidates[summary.chosen].folds) {
    EXPECT_LT(f.v_mae[1], f.v_mae[0]);
    EXPECT_LT(f.w_mae[1], f.w_mae[0]);
    EXPECT_GT(f.v_iteration, 0);
  }
  expect_beats_kinematics(test, model);
  // Same seed and tracks: the same nets, with any thread count.
  SelectionOptions two = quick_selection();
  two.training.num_threads = 2;
  const LearnedOdometryModel again = train_correction_odometry({&a, &b}, two, nullptr);
  EXPECT_TRUE(again.v_net == model.v_net);
  EXPECT_TRUE(again.w_net == model.w_net);
}

// The truth is exactly what the kinematic model says: no net can beat it on
// any fold, so the model is the kinematic odometry, bit for bit, and says so.
TEST(LearnedOdometry, ACorrectionWithoutGainIsTheKinematicOdometry) {
  auto exact = [](FusionInput in) {
    in.v_true = in.v_kin;
    in.w_true = in.w_kin;
    const PoseTrack p = dead_reckon(in, in.v_kin, in.w_kin);
    in.gt_x = p.x;
    in.gt_y = p.y;
    in.gt_theta = p.theta;
    return in;
  };
  const FusionInput a = exact(chair_input(60, 11)), b = exact(chair_input(60, 13));
  SelectionSummary summary;
  const LearnedOdometryModel model = train_correction_odometry({&a, &b}, quick_selection(), &summary);
  EXPECT_EQ(summary.combination, NetCombination::kinematic);
  EXPECT_FALSE(model.v_beats_kinematic);
  EXPECT_FALSE(model.w_beats_kinematic);
  const FusionInput test = chair_input(40, 12);
  const OdometrySeries learned = run_learned_odometry(test, model);
  for (std::size_t k = 1; k < test.size(); ++k) {
    ASSERT_EQ(learned.v[k], test.v_kin[k]) << k;
    ASSERT_EQ(learned.w[k], test.w_kin[k]) << k;
  }
  LearnedTarget t{};
  EXPECT_TRUE(parse_learned_target("correction", &t));
  EXPECT_EQ(t, LearnedTarget::correction);
  EXPECT_FALSE(parse_learned_target("residual", &t));
}

// A model reads one kind of odometry (and the gyro when it has one): a track
// that gives another is refused, naming both.
TEST(LearnedOdometry, AModelRefusesATrackWithoutItsInput) {
  const FusionInput wheels = chair_input(30, 5, {});
  LearnedOdometryModel m;
  m.target = LearnedTarget::correction;
  m.features = LearnedFeatures::channel;
  m.input = tracks::OdometryInput::commands;
  std::string why;
  EXPECT_FALSE(model_fits(m, wheels, &why));
  EXPECT_NE(why.find("gives wheels odometry, the model was trained on commands"), std::string::npos) << why;
  m.input = tracks::OdometryInput::wheels;
  m.ticks_per_rev = wheels.ticks_per_rev;
  EXPECT_TRUE(model_fits(m, wheels, &why)) << why;
  m.gyro = true;
  FusionInput no_gyro = wheels;
  no_gyro.has_gyro = false;
  EXPECT_FALSE(model_fits(m, no_gyro, &why));
  EXPECT_NE(why.find("no gyro"), std::string::npos) << why;
}

// One recording cut into blocks of block_s: the units the folds hold out;
// one recording with validation on recordings is refused.
TEST(LearnedOdometry, ValidationOnBlocksCutsOneRecording) {
  const FusionInput a = chair_input(120, 11);
  SelectionOptions o = quick_selection();
  o.training.max_iterations = 3;
  o.validation = LearnedValidation::blocks;
  o.block_s = 40.0;
  SelectionSummary s;
  train_correction_odometry({&a}, o, &s);
  // The drive lasts a little over 140 s: blocks from 0, 40, 80 and 120 s.
  const double end_s = a.t.back() - a.t.front();
  ASSERT_GT(end_s, 140.0);
  ASSERT_LT(end_s, 150.0);
  ASSERT_EQ(s.units.size(), 4u) << testing::PrintToString(s.units);
  EXPECT_NE(s.units[3].find("chair 120-"), std::string::npos) << s.units[3];
  EXPECT_EQ(s.folds, 4);
  // Blocks of 60 s: the last 25 s, under half a block, join the block before.
  o.block_s = 60.0;
  o.max_folds = 2;
  train_correction_odometry({&a}, o, &s);
  ASSERT_EQ(s.units.size(), 2u) << testing::PrintToString(s.units);
  EXPECT_NE(s.units[1].find("chair 60-14"), std::string::npos) << s.units[1];
  EXPECT_EQ(s.folds, 2);
  o.validation = LearnedValidation::recordings;
  EXPECT_THROW(train_correction_odometry({&a}, o, nullptr), std::invalid_argument);
  LearnedValidation v{};
  EXPECT_TRUE(parse_learned_validation("blocks", &v));
  EXPECT_EQ(v, LearnedValidation::blocks);
  EXPECT_FALSE(parse_learned_validation("random", &v));
}

// The paper's nets: validation on recordings holds the last tracks out
// whole; the nets train on every window of the others and on none of theirs.
TEST(LearnedOdometry, ValidationOnRecordingsHoldsWholeTracksOut) {
  const FusionInput a = chair_input(40, 11), b = chair_input(30, 12);
  auto windows = [](const FusionInput& in) {
    SequenceSet v, w;
    v.window = w.window = VelocityNet{}.window;
    v.inputs = w.inputs = VelocityNet::kInputs;
    WindowSpec spec;
    spec.window = v.window;
    append_velocity_windows(in, spec, &v, &w);
    return v.size();
  };
  LearnedTrainingOptions o = quick_training();
  o.training.max_iterations = 2;
  o.restarts = 1;
  o.validation = LearnedValidation::recordings;
  LearnedTrainingSummary s;
  train_learned_odometry({&a, &b}, o, &s);
  EXPECT_EQ(s.train_windows, windows(a));
  EXPECT_EQ(s.validation_windows, windows(b));
  o.validation = LearnedValidation::chronological;
  train_learned_odometry({&a, &b}, o, &s);
  EXPECT_GT(s.validation_windows, 0u);
  EXPECT_LT(s.validation_windows, windows(b));
  o.validation = LearnedValidation::recordings;
  EXPECT_THROW(train_learned_odometry({&a}, o, nullptr), std::invalid_argument);
}

TEST(LearnedOdometry, TrainingIsDeterministicAndRejectsTracksWithoutTruth) {
  const FusionInput train = chair_input(60, 11);
  LearnedTrainingOptions o = quick_training();
  o.training.max_iterations = 5;
  const LearnedOdometryModel a = train_learned_odometry({&train}, o, nullptr);
  const LearnedOdometryModel b = train_learned_odometry({&train}, o, nullptr);
  EXPECT_TRUE(a.v_net == b.v_net);
  EXPECT_TRUE(a.w_net == b.w_net);

  ChairTrackOptions no_gt;
  no_gt.duration_s = 30;
  no_gt.gt = false;
  const FusionInput blind = build_fusion_input(testing_support::chair_track(no_gt));
  try {
    train_learned_odometry({&blind}, o, nullptr);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ground truth"), std::string::npos) << e.what();
  }
}

// Online retraining (paper §4.2): a model trained before a tyre change,
// fused with the external velocities, refits itself every 300 good samples;
// after the change its odometry error falls below that of the same model
// without retraining.
TEST(LearnedFusion, RetrainingRecoversAfterARadiusStep) {
  const FusionInput train = chair_input(150, 21);
  const LearnedOdometryModel model = train_learned_odometry({&train}, quick_training(), nullptr);
  std::vector<std::string> step = kHiddenEffects;
  step.push_back("radius_step:t=30,scale_l=0.97,scale_r=1");
  const FusionInput drive = chair_input(150, 22, step);

  LearnedFusionOptions o;
  o.static_var_v = o.static_var_w = 1e-3;
  LearnedFusionOptions with = o;
  with.retrain.enabled = true;
  with.retrain.training.max_iterations = 10;
  const LearnedFusionResult off = run_learned_fusion(drive, &model, o);
  const LearnedFusionResult on = run_learned_fusion(drive, &model, with);
  ASSERT_TRUE(off.filter.healthy);
  ASSERT_TRUE(on.filter.healthy);
  EXPECT_TRUE(off.retrains.empty());
  ASSERT_GE(on.retrains.size(), 2u);
  for (const RetrainEvent& ev : on.retrains) EXPECT_GT(ev.t_s, 0.0);

  // Odometry W error over the last third of the drive (well after the step
  // and after at least one refit).
  const std::size_t from = drive.size() * 2 / 3;
  auto tail_w_mae = [&](const OdometrySeries& s) {
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t k = from; k < drive.size(); ++k)
      if (std::isfinite(drive.w_true[k])) sum += std::abs(s.w[k] - drive.w_true[k]), ++n;
    return sum / static_cast<double>(n);
  };
  EXPECT_LT(tail_w_mae(on.odometry), 0.7 * tail_w_mae(off.odometry));
  ASSERT_TRUE(on.final_model.has_value());
  EXPECT_FALSE(on.final_model->w_net == model.w_net);
}

TEST(LearnedFusion, InvalidOptionsAreOneLineErrors) {
  const FusionInput in = chair_input(30, 5, {});
  LearnedFusionOptions o;
  o.odometry = LearnedFusionOptions::Odometry::kinematic;
  o.retrain.enabled = true;
  EXPECT_THROW(run_learned_fusion(in, nullptr, o), std::invalid_argument);
  o.retrain.enabled = false;
  o.static_var_v = -1;
  EXPECT_THROW(run_learned_fusion(in, nullptr, o), std::invalid_argument);
  o.static_var_v = 1e-3;
  o.odometry = LearnedFusionOptions::Odometry::learned;
  EXPECT_THROW(run_learned_fusion(in, nullptr, o), std::invalid_argument);
  o.odometry = LearnedFusionOptions::Odometry::kinematic;
  const LearnedFusionResult r = run_learned_fusion(in, nullptr, o);
  EXPECT_TRUE(r.filter.healthy);
  EXPECT_FALSE(r.final_model.has_value());
}

}  // namespace
}  // namespace odotune::learned

namespace odotune::learned {
namespace {

// A chair track with motor power (the wheelchair's drive train of
// scenarios/wheelchair.yaml) and slip episodes at random times, seeded by
// `seed`: gaps of 4–10 s, durations of 2–5 s, peak strengths 0.3–0.8, kind
// (spin/hold) and wheel drawn at random, the first within 4 s of `offset_s`.
// The uniform draws are SplitMix64 (fixed by its definition, unlike
// std::uniform_real_distribution), so the episodes are the same everywhere.
FusionInput slip_input(double duration_s, std::uint64_t seed, double offset_s,
                       std::vector<sim::SlipEpisode>* episodes_out = nullptr) {
  ChairTrackOptions o;
  o.duration_s = duration_s;
  o.seed = seed;
  sim::Scenario sc = testing_support::chair_scenario(o);
  sc.robot.mass_kg = 130.0;
  sc.robot.yaw_inertia_kg_m2 = 18.0;
  sc.robot.wheel_inertia_kg_m2 = 0.4;
  sc.robot.viscous_friction_nm_s = 0.5;
  sc.robot.coulomb_friction_nm = 3.0;
  sc.robot.coulomb_smoothing_rad_s = 0.2;
  sc.robot.torque_constant_nm_per_a = 8.0;
  sc.robot.coil_resistance_ohm = 0.3;
  sc.sensors.power.enabled = true;
  sc.sensors.power.rate_hz = 100.0;
  sc.sensors.power.sigma_w = 0.5;
  std::uint64_t state = seed * 7919u + 13u;
  auto uniform = [&state] {  // SplitMix64 → [0, 1)
    state += 0x9E3779B97F4A7C15ull;
    std::uint64_t z = state;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  };
  for (double t = offset_s + 4.0 * uniform();;) {
    sim::SlipEpisode e;
    const double d = 2.0 + 3.0 * uniform();
    if (t + d > duration_s - 3.0) break;
    e.kind = uniform() < 0.5 ? sim::SlipEpisode::Kind::spin : sim::SlipEpisode::Kind::hold;
    e.wheel = uniform() < 0.5 ? sim::SlipEpisode::Wheel::left : sim::SlipEpisode::Wheel::right;
    e.t0_s = t;
    e.t1_s = t + d;
    e.s = 0.3 + 0.5 * uniform();
    sc.slip_episodes.push_back(e);
    t += d + 4.0 + 6.0 * uniform();
  }
  if (episodes_out) *episodes_out = sc.slip_episodes;
  return build_fusion_input(sim::simulate(sc));
}

// Paper §4.1, Fig. 6: the detector's variance stays low while the wheels
// grip and rises during slip. Trained on four drives, checked on another
// drive (other noise, episodes at other times, kinds and strengths).
TEST(SlipDetector, VarianceRisesDuringSimulatedSlipAndStaysLowElsewhere) {
  std::vector<FusionInput> drives;
  for (std::uint64_t seed = 31; seed < 35; ++seed) drives.push_back(slip_input(200, seed, 8.0));
  std::vector<const FusionInput*> train;
  std::vector<OdometrySeries> odometry;
  for (const FusionInput& d : drives) {
    ASSERT_TRUE(d.has_power);
    train.push_back(&d);
    odometry.push_back(kinematic_odometry(d));
  }
  std::vector<sim::SlipEpisode> episodes;
  const FusionInput test = slip_input(120, 202, 6.0, &episodes);
  SlipTrainingOptions o;  // defaults: no teacher forcing, one feedback round, weight decay
  o.training.max_iterations = 30;
  o.stride = 8;
  SlipTrainingSummary summary;
  const SlipDetectorModel det = train_slip_detector(train, odometry, o, &summary);
  EXPECT_TRUE(summary.v.usable);
  EXPECT_TRUE(summary.w.usable);

  SlipDetectorStepper stepper(&det);
  std::vector<double> inside, outside;
  for (std::size_t k = 1; k < test.size(); ++k) {
    const auto var = stepper.step(test, k);
    const double t = test.t[k];
    bool in = false, near = false;
    for (const auto& e : episodes) {
      in = in || (t >= e.t0_s + 0.5 && t <= e.t1_s);
      near = near || (t >= e.t0_s - 1.0 && t <= e.t1_s + 2.5);  // the window's memory
    }
    if (in)
      inside.push_back(var[1] + var[0]);
    else if (!near && k > 25)
      outside.push_back(var[1] + var[0]);
  }
  ASSERT_GT(inside.size(), 50u);
  ASSERT_GT(outside.size(), 300u);
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double med_in = median(inside), med_out = median(outside);
  EXPECT_GT(med_in, 5.0 * med_out) << "inside " << med_in << " outside " << med_out;
  // "Stays low": 90 % of the grip steps below the inside median / 3.
  std::size_t low = 0;
  for (double v : outside) low += v < med_in / 3.0 ? 1 : 0;
  EXPECT_GT(static_cast<double>(low), 0.9 * static_cast<double>(outside.size()));
}

}  // namespace
}  // namespace odotune::learned

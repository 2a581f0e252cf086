#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/objectives/ekf_objective.h>
#include <odotune/objectives/param_space.h>
#include <odotune/objectives/replay.h>
#include <odotune/objectives/replay_input.h>

#include "support/synthetic_track.h"

namespace odotune::objectives {
namespace {

using filters::NoiseModel;
using filters::NoiseParams;

TEST(Metrics, FitnessModesCombineRmseMaeMaxe) {
  ErrorAccumulator acc;
  for (double e : {0.1, 0.2, 0.4}) acc.add(e);
  const ErrorMetrics m = acc.metrics();
  EXPECT_NEAR(m.rmse_m, std::sqrt((0.01 + 0.04 + 0.16) / 3), 1e-15);
  EXPECT_NEAR(m.mae_m, 0.7 / 3, 1e-15);
  EXPECT_DOUBLE_EQ(m.maxe_m, 0.4);
  EXPECT_DOUBLE_EQ(fitness_of(m, FitnessMode::rmse), m.rmse_m);
  EXPECT_DOUBLE_EQ(fitness_of(m, FitnessMode::mae), m.mae_m);
  EXPECT_DOUBLE_EQ(fitness_of(m, FitnessMode::maxe), m.maxe_m);
  EXPECT_DOUBLE_EQ(fitness_of(m, FitnessMode::rmse_mae), m.rmse_m + m.mae_m);
  EXPECT_DOUBLE_EQ(fitness_of(m, FitnessMode::rmse_maxe), m.rmse_m + m.maxe_m);
  EXPECT_DOUBLE_EQ(fitness_of(m, FitnessMode::mae_maxe), m.mae_m + m.maxe_m);
  EXPECT_DOUBLE_EQ(fitness_of(m, FitnessMode::rmse_mae_maxe), m.rmse_m + m.mae_m + m.maxe_m);
  EXPECT_EQ(fitness_mode_name(FitnessMode::rmse_mae_maxe), "RMSE+MAE+MAXE");
}

TEST(ParamSpace, StudyBoundsAndLogScaling) {
  const ParamSpace rq = ParamSpace::for_model(NoiseModel::rq);
  ASSERT_EQ(rq.dim(), 5u);
  EXPECT_EQ(rq.params()[0].name, "r1_mm2");
  EXPECT_DOUBLE_EQ(rq.params()[2].lower, 1e-6);
  EXPECT_TRUE(rq.params()[3].log_scale);
  const auto [lo, hi] = rq.box();
  EXPECT_DOUBLE_EQ(lo[0], 0.0);
  EXPECT_DOUBLE_EQ(hi[0], 5.0);
  EXPECT_DOUBLE_EQ(lo[2], -6.0);
  // A box point maps to SI noise: r1 = 10^2 mm² = 1e-4 m².
  const NoiseParams n = rq.to_noise(rq.to_physical(std::vector<double>{2, 3, -2, 1, 4}));
  EXPECT_NEAR(n.r_x_m2, 1e-4, 1e-18);
  EXPECT_NEAR(n.r_y_m2, 1e-3, 1e-18);
  EXPECT_NEAR(n.r_theta_rad2, 1e-2, 1e-18);
  EXPECT_NEAR(n.q_x_m2, 1e-5, 1e-18);
  EXPECT_NEAR(n.q_y_m2, 1e-2, 1e-16);
  // Round trip physical → box → physical.
  const std::vector<double> phys{123, 4567, 0.003, 50, 900};
  const auto back = rq.to_physical(rq.to_box(phys));
  for (std::size_t i = 0; i < phys.size(); ++i) EXPECT_NEAR(back[i], phys[i], 1e-9 * phys[i]);

  const ParamSpace gyro = ParamSpace::for_model(NoiseModel::gyro);
  EXPECT_EQ(gyro.dim(), 4u);
  EXPECT_FALSE(gyro.params()[2].log_scale);  // [0, 5] cannot be log-scaled
  EXPECT_DOUBLE_EQ(gyro.box().second[2], 5.0);
  // Out-of-box coordinates are clamped to the bounds.
  const auto clamped = gyro.to_physical(std::vector<double>{-1, 2, 9, 0.5});
  EXPECT_DOUBLE_EQ(clamped[0], 0.0);
  EXPECT_DOUBLE_EQ(clamped[1], 1.0);
  EXPECT_DOUBLE_EQ(clamped[2], 5.0);
  EXPECT_EQ(ParamSpace::for_model(NoiseModel::alpha).dim(), 2u);
}

TEST(ReplayInput, StartsAtFirstGroundTruthAndConvertsTicks) {
  const tracks::Track track = testing_support::synthetic_track(1, 10.0);
  const ReplayInput in = build_replay_input(track);
  EXPECT_EQ(in.source, OdometrySource::ticks);
  EXPECT_EQ(in.steps.size(), track.size() - 1);
  EXPECT_EQ(in.fixes.size(), 9u);  // at 1 s … 9 s
  EXPECT_EQ(in.gt.size(), track.size() - 1);
  // Total dead-reckoned distance ≈ 0.4 m/s × 10 s.
  double dist = 0;
  for (auto u : in.steps) dist += 0.5 * (u.left_m + u.right_m);
  EXPECT_NEAR(dist, 0.4 * (10.0 - 0.02), 0.01);
}

TEST(ReplayInput, RejectsTrackWithoutGroundTruth) {
  tracks::TrackData d;
  d.meta.name = "nogt";
  d.t = {0, 1};
  d.col(tracks::Col::v_cmd) = {0, 0};
  d.col(tracks::Col::w_cmd) = {0, 0};
  try {
    build_replay_input(tracks::Track(std::move(d)));
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nogt"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("ground truth"), std::string::npos);
  }
}

class FastVsStep : public ::testing::TestWithParam<NoiseModel> {};

// The tuner's fast replay reproduces the reference replay's metrics.
TEST_P(FastVsStep, SameMetrics) {
  const tracks::Track track = testing_support::synthetic_track(2);
  const ReplayInput in = build_replay_input(track);
  const FastReplay fast(in);
  const ParamSpace space = ParamSpace::for_model(GetParam());
  std::mt19937_64 rng(3);
  const auto [lo, hi] = space.box();
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> x(space.dim());
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::uniform_real_distribution<double>(lo[i], hi[i])(rng);
    const NoiseParams noise = space.to_noise(space.to_physical(x));
    const ReplayResult ref = replay_ekf(in, noise);
    const ReplayOutcome got = fast.evaluate(noise);
    ASSERT_EQ(got.divergence, ref.outcome.divergence);
    EXPECT_EQ(got.metrics.samples, ref.outcome.metrics.samples);
    EXPECT_NEAR(got.metrics.rmse_m, ref.outcome.metrics.rmse_m, 1e-9);
    EXPECT_NEAR(got.metrics.mae_m, ref.outcome.metrics.mae_m, 1e-9);
    EXPECT_NEAR(got.metrics.maxe_m, ref.outcome.metrics.maxe_m, 1e-9);
  }
}

INSTANTIATE_TEST_SUITE_P(AllModels, FastVsStep,
                         ::testing::Values(NoiseModel::rq, NoiseModel::alpha, NoiseModel::gyro),
                         [](const auto& p) { return std::string(filters::to_string(p.param)); });

TEST(Replay, FixesBoundTheErrorThatDeadReckoningAccumulates) {
  const tracks::Track track = testing_support::synthetic_track(4);
  const ReplayInput in = build_replay_input(track);
  NoiseParams trust_odometry = baseline_noise();
  trust_odometry.a1 = trust_odometry.a2 = 0.0;  // R = 0: the fixes can never pull the pose
  NoiseParams fuse = baseline_noise();
  fuse.a1 = fuse.a2 = 0.05;  // odometry trusted to 5 %: the fixes pull the pose
  const ReplayResult dr = replay_ekf(in, trust_odometry);
  const ReplayResult fused = replay_ekf(in, fuse, true);
  EXPECT_GT(dr.outcome.metrics.maxe_m, 0.3);  // 1 % radius error over ~24 m
  EXPECT_LT(fused.outcome.metrics.rmse_m, 0.5 * dr.outcome.metrics.rmse_m);
  EXPECT_EQ(fused.trajectory.size(), in.gt.size() + 1);
}

TEST(EkfObjective, PenalisesAndCountsDivergence) {
  // A track whose fix is absurdly far away with tiny measurement noise and
  // huge odometry noise drives the covariance update into cancellation.
  const tracks::Track track = testing_support::synthetic_track(5, 5.0);
  ReplayInput in = build_replay_input(track);
  for (auto& z : in.fixes) z = filters::Position(std::nan(""), 0.0);
  const FastReplay fast(in);
  const EkfObjective obj({&fast}, NoiseModel::alpha, FitnessMode::rmse);
  const double f = obj.fitness(std::vector<double>{0.1, 0.1});
  EXPECT_EQ(f, kDivergencePenalty);
  EXPECT_EQ(obj.divergences().non_finite, 1);
  EXPECT_EQ(obj.evaluations(), 1);
}

TEST(EkfObjective, MeanOverTracksAndBaselineIsBeatable) {
  const tracks::Track a = testing_support::synthetic_track(6), b = testing_support::synthetic_track(7);
  const FastReplay fa(build_replay_input(a)), fb(build_replay_input(b));
  const EkfObjective both({&fa, &fb}, NoiseModel::alpha, FitnessMode::rmse_mae_maxe);
  const EkfObjective only_a({&fa}, NoiseModel::alpha, FitnessMode::rmse_mae_maxe);
  const EkfObjective only_b({&fb}, NoiseModel::alpha, FitnessMode::rmse_mae_maxe);
  const std::vector<double> x{0.02, 0.3};
  EXPECT_NEAR(both.fitness(x), 0.5 * (only_a.fitness(x) + only_b.fitness(x)), 1e-15);
  EXPECT_THROW(EkfObjective({}, NoiseModel::alpha, FitnessMode::rmse), std::invalid_argument);
  EXPECT_THROW(EkfObjective({&fa}, NoiseModel::alpha, FitnessMode::fix_rmse), std::invalid_argument);
}

}  // namespace
}  // namespace odotune::objectives

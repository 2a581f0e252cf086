// Fix cross-validation (odotune/objectives/fix_cv_replay.h) and the replay from the
// first fix (ReplayReference::fixes): the held-out prediction equals the
// one-step EKF's; the heading fit; per-fix variances; the scores rank noise
// settings as ground truth does; refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <odotune/filters/ekf.h>
#include <odotune/objectives/ekf_objective.h>
#include <odotune/objectives/fix_cv_replay.h>
#include <odotune/objectives/param_space.h>
#include <odotune/objectives/replay.h>
#include <odotune/objectives/replay_input.h>

#include "support/synthetic_track.h"

namespace odotune::objectives {
namespace {

using filters::NoiseModel;

ReplayInput by_fixes(const tracks::Track& t) {
  ReplayInputOptions o;
  o.reference = ReplayReference::fixes;
  return build_replay_input(t, o);
}

filters::NoiseParams alpha(double a1, double a2) {
  filters::NoiseParams n;
  n.model = NoiseModel::alpha;
  n.a1 = a1;
  n.a2 = a2;
  return n;
}

// The held-out scores recomputed with the one-step filter (odotune/filters/ekf.h):
// for each fold, predict over every step, apply the fixes of other folds,
// and compare the prediction with each held-out fix.
FixCvOutcome reference_cv(const ReplayInput& in, const FixCvOptions& cv, const filters::NoiseParams& noise) {
  ErrorAccumulator acc;
  double nll = 0.0, nis = 0.0;
  for (int k = 0; k < cv.folds; ++k) {
    filters::Ekf ekf(ekf_params_for(in, noise));
    for (const ReplayRow& row : in.rows) {
      if (row.step >= 0) ekf.predict(in.steps[row.step], in.abs_yaw_rate_rad_s[row.step]);
      if (row.fix < 0) continue;
      const auto block = static_cast<long>(std::floor((row.t_s - in.t0_s) / cv.block_s));
      if (block % cv.folds != k) {
        ekf.update(in.fixes[row.fix]);
        continue;
      }
      const Eigen::Vector2d e = in.fixes[row.fix] - ekf.pose().head<2>();
      const Eigen::Matrix2d S = ekf.cov().topLeftCorner<2, 2>() +
                                Eigen::Vector2d(noise.q_x_m2, noise.q_y_m2).asDiagonal().toDenseMatrix();
      const double m = e.dot(S.inverse() * e);
      acc.add(e.norm());
      nis += m;
      nll += 0.5 * m + 0.5 * std::log(S.determinant()) + std::log(2.0 * std::numbers::pi);
    }
  }
  FixCvOutcome out;
  out.heldout = acc.metrics();
  out.nll = nll / static_cast<double>(acc.n);
  out.nis = nis / static_cast<double>(acc.n);
  return out;
}

TEST(FixCvReplay, EqualsTheOneStepFilter) {
  const tracks::Track tr = testing_support::synthetic_track(3, 120.0);
  const ReplayInput in = by_fixes(tr);
  const FixCvOptions cv;
  const FixCvReplay replay(in, cv);
  EXPECT_EQ(replay.heldout_fixes(), static_cast<long>(in.fixes.size()));  // every fix is held out once
  for (const auto& noise : {alpha(0.01, 0.01), alpha(0.2, 0.05)}) {
    const FixCvOutcome a = replay.evaluate(noise), b = reference_cv(in, cv, noise);
    EXPECT_NEAR(a.heldout.rmse_m, b.heldout.rmse_m, 1e-9);
    EXPECT_NEAR(a.heldout.maxe_m, b.heldout.maxe_m, 1e-9);
    EXPECT_NEAR(a.nll, b.nll, 1e-8);
    EXPECT_NEAR(a.nis, b.nis, 1e-8);
    EXPECT_EQ(a.heldout.samples, b.heldout.samples);
  }
}

TEST(FixCvReplay, HeadingFittedFromTheFixes) {
  // The same drive turned by 1 rad about the origin: its ground truth starts
  // at heading 1; the fit must find it from odometry and noisy fixes alone.
  const tracks::Track base = testing_support::synthetic_track(5, 120.0);
  tracks::TrackData d;
  d.meta = base.meta();
  d.t = base.t();
  d.ticks_l = base.ticks_l();
  d.ticks_r = base.ticks_r();
  const double c = std::cos(1.0), s = std::sin(1.0);
  for (tracks::Col k : {tracks::Col::aps_x, tracks::Col::aps_y}) d.ensure(k);
  for (std::size_t i = 0; i < base.size(); ++i) {
    const double x = base.col(tracks::Col::aps_x)[i], y = base.col(tracks::Col::aps_y)[i];
    d.col(tracks::Col::aps_x)[i] = 5.0 + c * x - s * y;
    d.col(tracks::Col::aps_y)[i] = -2.0 + s * x + c * y;
  }
  const ReplayInput in = by_fixes(tracks::Track(std::move(d)));
  std::size_t first = 0;
  while (std::isnan(base.col(tracks::Col::aps_x)[first])) ++first;
  // Within the (10°)² the replay then assumes: this odometry's right wheel is
  // 1 % off, so its own heading drifts 0.013 rad/s while the fit runs.
  EXPECT_NEAR(in.initial_pose(2), 1.0 + base.col(tracks::Col::gt_theta)[first], 0.1);
  EXPECT_NE(in.initial_pose_note.find("heading"), std::string::npos);
  EXPECT_GT(in.initial_cov(2, 2), 0.01);  // (10°)²
}

TEST(FixCvReplay, RanksNoiseAsGroundTruthDoes) {
  // On simulated drives, the noise that scores best held out is near the
  // one that scores best against ground truth, and both beat a bad one.
  const tracks::Track tr = testing_support::synthetic_track(11, 300.0);
  const FixCvReplay cv(by_fixes(tr), {});
  const FastReplay gt(build_replay_input(tr));
  double best_cv = 1e300, best_gt = 1e300;
  double a_cv = 0, a_gt = 0;
  for (double a1 : {0.001, 0.003, 0.01, 0.03, 0.1, 0.3}) {
    const auto n = alpha(a1, a1);
    const double f_cv = cv.evaluate(n).nll, f_gt = gt.evaluate(n).metrics.rmse_m;
    if (f_cv < best_cv) best_cv = f_cv, a_cv = a1;
    if (f_gt < best_gt) best_gt = f_gt, a_gt = a1;
  }
  EXPECT_LE(std::abs(std::log10(a_cv) - std::log10(a_gt)), 0.6) << a_cv << " vs " << a_gt;
  // The ground-truth error at the held-out choice is within 10 % of the best.
  EXPECT_LE(gt.evaluate(alpha(a_cv, a_cv)).metrics.rmse_m, 1.1 * best_gt);
}

TEST(FixCvReplay, PerFixVariancesReplaceTheModelsQ) {
  const tracks::Track base = testing_support::synthetic_track(4, 60.0);
  tracks::TrackData d;
  d.meta = base.meta();
  d.t = base.t();
  d.ticks_l = base.ticks_l();
  d.ticks_r = base.ticks_r();
  for (int c = 0; c < tracks::kNumCols; ++c) d.cols[c] = base.col(static_cast<tracks::Col>(c));
  d.ensure(tracks::Col::aps_var_x);
  d.ensure(tracks::Col::aps_var_y);
  for (std::size_t i = 0; i < base.size(); ++i)
    if (!std::isnan(base.col(tracks::Col::aps_x)[i]))
      d.col(tracks::Col::aps_var_x)[i] = d.col(tracks::Col::aps_var_y)[i] = 0.25;
  const tracks::Track tr(std::move(d));
  const ReplayInput with = build_replay_input(tr), without = build_replay_input(base);
  auto noise = alpha(0.02, 0.02);
  // The fast replay agrees with the reference with per-fix variances too.
  const double ref = replay_ekf(with, noise).outcome.metrics.rmse_m;
  EXPECT_NEAR(FastReplay(with).evaluate(noise).metrics.rmse_m, ref, 1e-9);
  // And they matter: the same as the model's Q set to 0.25 m².
  auto q = noise;
  q.q_x_m2 = q.q_y_m2 = 0.25;
  EXPECT_NEAR(replay_ekf(without, q).outcome.metrics.rmse_m, ref, 1e-12);
  EXPECT_GT(std::abs(replay_ekf(without, noise).outcome.metrics.rmse_m - ref), 1e-4);
}

TEST(FixCvReplay, Refusals) {
  const tracks::Track tr = testing_support::synthetic_track(2, 60.0);
  FixCvOptions o;
  o.folds = 1;
  EXPECT_THROW(FixCvReplay(by_fixes(tr), o), std::invalid_argument);
  o.folds = 5;
  o.block_s = 100.0;  // one block: the other folds hold out nothing
  EXPECT_THROW(FixCvReplay(by_fixes(tr), o), std::invalid_argument);
  // The objective: modes 8 and 9 only, over fixes; and a mode 1..7 tune needs ground truth.
  const FixCvReplay cv(by_fixes(tr), {});
  EXPECT_THROW(EkfObjective::over_fixes({&cv}, NoiseModel::alpha, FitnessMode::rmse_mae_maxe),
               std::invalid_argument);
  const EkfObjective obj = EkfObjective::over_fixes({&cv}, NoiseModel::alpha, FitnessMode::fix_rmse);
  EXPECT_NEAR(obj.fitness(std::vector<double>{0.01, 0.01}), cv.evaluate(alpha(0.01, 0.01)).heldout.rmse_m,
              1e-15);
  tracks::TrackData d;
  d.meta = tr.meta();
  d.t = tr.t();
  d.ticks_l = tr.ticks_l();
  d.ticks_r = tr.ticks_r();
  d.col(tracks::Col::gt_x) = tr.col(tracks::Col::gt_x);
  d.col(tracks::Col::gt_y) = tr.col(tracks::Col::gt_y);
  EXPECT_THROW(by_fixes(tracks::Track(std::move(d))), std::invalid_argument);  // no fixes
}

}  // namespace
}  // namespace odotune::objectives

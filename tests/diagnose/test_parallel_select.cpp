// The model selection's parallel batches (cross_validate.h
// cross_validate_all, diagnosis-design.md "Model selection", "Deterministic") give the same numbers as
// one fit at a time, for any number of OpenMP threads. Tracks simulated in
// memory (sim_track.h): 50 Hz odometry and ground truth with 5 mm noise.
#include <omp.h>

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/diagnose/cross_validate.h>
#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/select.h>

#include "diagnose/sim_track.h"

namespace odotune::diagnose {
namespace {

DiagInput track(double duration_s, std::vector<std::string> effects) {
  testing_support::SimTrackOptions o;
  o.duration_s = duration_s;
  o.seed = 11;
  o.odo_rate_hz = 50.0, o.gt_rate_hz = 50.0, o.gt_sigma_m = 0.005;
  o.effects = std::move(effects);
  return build_diag_input(testing_support::simulate_track(o));
}

// Runs f with n OpenMP threads, restoring the previous count.
template <typename F>
auto with_threads(int n, F f) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(n);
  auto out = f();
  omp_set_num_threads(before);
  return out;
}

void expect_same(const SetEval& a, const SetEval& b, const std::string& what) {
  ASSERT_EQ(a.ok, b.ok) << what;
  EXPECT_EQ(a.score, b.score) << what;  // bit for bit
  EXPECT_EQ(a.window_sse, b.window_sse) << what;
  ASSERT_EQ(a.folds.size(), b.folds.size()) << what;
  for (std::size_t f = 0; f < a.folds.size(); ++f)
    EXPECT_EQ(a.folds[f].to_string(), b.folds[f].to_string()) << what << ", fold " << f;
}

TEST(ParallelSelect, BatchOfSetsEqualsOneSetAtATimeWithAnyThreadCount) {
  const DiagInput in = track(100.0, {"radius_error:scale_l=0.99,scale_r=1.01", "lateral_skid:k=0.03"});
  FitOptions fit = default_select_fit();
  fit.window_s = 20.0;
  const std::vector<EffectSet> sets = {EffectSet().enable(Effect::radius_error),
                                       EffectSet().enable(Effect::lateral_skid), EffectSet()};
  CrossValidator serial(in, fit, 5);
  std::vector<SetEval> one;
  for (const EffectSet& s : sets)
    one.push_back(with_threads(1, [&] { return serial.cross_validate(s, {}, 30); }));
  for (int threads : {1, 2, 3}) {
    CrossValidator cv(in, fit, 5);
    const std::vector<SetEval> batch = with_threads(threads,
                                                    [&] { return cv.cross_validate_all(sets, {}, 30); });
    ASSERT_EQ(batch.size(), sets.size());
    for (std::size_t i = 0; i < sets.size(); ++i)
      expect_same(one[i], batch[i], sets[i].to_string() + " with " + std::to_string(threads) + " threads");
    EXPECT_EQ(cv.fits(), 10) << "two non-empty sets x 5 folds";
  }
  // The fits must have done something: radius_error beats the nominal model.
  EXPECT_LT(one[0].score, 0.5 * one[2].score);
}

TEST(ParallelSelect, SelectionIsTheSameWithOneAndTwoThreads) {
  const DiagInput in = track(120.0, {"radius_error:scale_l=0.99,scale_r=1.01"});
  SelectOptions o;
  o.candidates = {Effect::radius_error, Effect::radius_step, Effect::lateral_skid, Effect::slip_zone};
  const Selection a = with_threads(1, [&] { return select_effects(in, o); });
  const Selection b = with_threads(2, [&] { return select_effects(in, o); });
  EXPECT_EQ(a.structure.to_string(), b.structure.to_string());
  ASSERT_EQ(a.records.size(), b.records.size());
  for (std::size_t i = 0; i < a.records.size(); ++i) {
    EXPECT_EQ(a.records[i].set, b.records[i].set) << i;
    const double x = a.records[i].cv_score, y = b.records[i].cv_score;  // NaN: not evaluated
    EXPECT_TRUE(x == y || (std::isnan(x) && std::isnan(y)))
        << i << " " << a.records[i].set << ": " << x << " vs " << y;
    EXPECT_EQ(a.records[i].accepted, b.records[i].accepted) << i;
  }
  ASSERT_TRUE(a.fitted);
  ASSERT_EQ(a.final_fit.params.size(), b.final_fit.params.size());
  for (std::size_t i = 0; i < a.final_fit.params.size(); ++i)
    EXPECT_EQ(a.final_fit.params[i].value, b.final_fit.params[i].value) << a.final_fit.params[i].name;
  EXPECT_TRUE(a.structure.on(Effect::radius_error)) << a.structure.to_string();
}

}  // namespace
}  // namespace odotune::diagnose

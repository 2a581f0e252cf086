// The study's claim on our reference tracks: for every track and every noise
// model, PSO tuning beats the untuned baseline's RMSE. Reduced budget (the
// full 50 × 150 is the demo's and the benchmark's).
#include <gtest/gtest.h>

#include <odotune/jobs/tune_job.h>
#include <odotune/tracks/track_io.h>

#include "support/cli_runner.h"

namespace odotune::jobs {
namespace {

using filters::NoiseModel;

class ReferenceTuning : public ::testing::TestWithParam<std::tuple<int, NoiseModel>> {};

TEST_P(ReferenceTuning, PsoBeatsBaselineRmse) {
  const auto [index, model] = GetParam();
  const tracks::Track track = tracks::read_track(testing_support::reference_track(index));
  const odotune::jobs::PreparedTrack prepared = odotune::jobs::prepare_track(track);
  odotune::jobs::TuneRequest req;
  req.model = model;
  req.mode = odotune::objectives::FitnessMode::rmse;
  req.seed = 42;
  req.particles = 16;
  req.iterations = 20;
  const odotune::jobs::TuneOutcome out = odotune::jobs::run_tune({&prepared}, req);
  EXPECT_LT(out.tuned_mean.rmse_m, out.baseline_mean.rmse_m)
      << "track" << index << " " << filters::to_string(model);
  EXPECT_EQ(out.summary.evaluations, 16 * 21);
}

INSTANTIATE_TEST_SUITE_P(
    AllTracksAllModels, ReferenceTuning,
    ::testing::Combine(::testing::Range(1, 6),
                       ::testing::Values(NoiseModel::rq, NoiseModel::alpha, NoiseModel::gyro)),
    [](const auto& p) {
      return "track" + std::to_string(std::get<0>(p.param)) + "_" +
             std::string(filters::to_string(std::get<1>(p.param)));
    });

}  // namespace
}  // namespace odotune::jobs

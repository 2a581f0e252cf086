// The names a results store keeps are data (odotune/results/run_record.h),
// parsed where a job reads them back: a run's model (odotune/jobs/store_access.h)
// and export's --select keys (odotune/jobs/export_job.h) become types once,
// and a name that is none is refused in one line.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/core/failure.h>
#include <odotune/jobs/export_job.h>
#include <odotune/jobs/store_access.h>

namespace odotune::jobs {
namespace {

results::RunRecord stored_run_of(const std::string& model) {
  results::RunRecord r;
  r.model = model;
  r.track = "track1";
  r.mode = 7;
  r.seed = 3;
  return r;
}

TEST(StoreChoices, AStoredModelIsParsedOnce) {
  EXPECT_EQ(run_model(stored_run_of("gyro")), objectives::TunedModel::ekf(filters::NoiseModel::gyro));
  EXPECT_TRUE(run_model(stored_run_of("adaptive-pf-calib")).is_calibrator());
  EXPECT_TRUE(run_model(stored_run_of("ukf")).is_ukf());
  EXPECT_EQ(stored_model("rl-ukf"), objectives::TunedModel::rl(filters::rl::RlFilterType::ukf));
  for (const objectives::TunedModel& m : objectives::kAllTunedModels)
    EXPECT_EQ(stored_model(objectives::to_string(m)), m) << objectives::to_string(m);
}

TEST(StoreChoices, AnUnknownStoredModelNamesTheRun) {
  const results::RunRecord r = stored_run_of("kalman");
  try {
    run_model(r);
    ADD_FAILURE() << "kalman was taken for a model";
  } catch (const core::Failure& f) {
    const std::string what = f.what();
    EXPECT_NE(what.find(results::run_key(r)), std::string::npos) << what;
    EXPECT_NE(what.find("unknown model 'kalman'"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_THROW(run_noise(r), core::Failure);
}

TEST(StoreChoices, SelectKeysAreParsedIntoRunKeys) {
  const std::vector<RunFilter> f = parse_run_filters({"mode=07", "heldout=none", "model=rq"});
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(f[0].key, RunKey::mode);
  EXPECT_EQ(f[0].value, "7");
  EXPECT_EQ(f[1].key, RunKey::heldout);
  EXPECT_EQ(f[2].text(), "model=rq");
  try {
    parse_run_filters({"colour=red"});
    ADD_FAILURE() << "colour was taken for a key";
  } catch (const core::Failure& e) {
    EXPECT_NE(
        std::string(e.what()).find("unknown key 'colour', expected one of model, track, mode, seed, heldout"),
        std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace odotune::jobs

// The diagnosis of real recordings gives the same numbers, bit for bit, with
// one or two OpenMP threads and on every run: three OptiOdom runs
// (../shared/data/real/optiodom_diff, SOURCE.md), two fitted pooled and one
// held out, the path that runs every step (selection, fits with standard
// errors, the term search, per-recording refits). Compared as the JSON the
// command writes, without its timing.
#include <omp.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/recordings.h>
#include <odotune/formats/diagnosis_json.h>
#include <odotune/tracks/importers.h>

namespace odotune::diagnose {
namespace {

DiagInput optiodom_run(const std::string& run) {
  const std::string dir = std::string(ODOTUNE_SHARED_DIR) + "/data/real/optiodom_diff/";
  return build_diag_input(tracks::import_optiodom(dir + run + ".csv"));
}

// Removes every "timing_s" object: wall-clock seconds differ from run to run.
void drop_timing(nlohmann::json& j) {
  if (j.is_object()) j.erase("timing_s");
  if (j.is_structured())
    for (auto& v : j) drop_timing(v);
}

// The pooled diagnosis's JSON with n threads, its timing removed.
std::string pooled_json_with_threads(int n, const std::vector<DiagInput>& fit,
                                     const std::vector<DiagInput>& heldout) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(n);
  nlohmann::json j = formats::pooled_diagnosis_json(diagnose_recordings(fit, heldout, DiagnoseOptions{}));
  omp_set_num_threads(before);
  drop_timing(j);
  return j.dump(1);
}

TEST(ThreadCount, PooledDiagnosisOfRealRecordingsIsTheSameWithOneAndTwoThreads) {
  const std::vector<DiagInput> fit = {optiodom_run("free/030120210001/030120210001_run-01"),
                                      optiodom_run("circular/231220200146/231220200146_run-01")};
  const std::vector<DiagInput> heldout = {optiodom_run("free/030120210001/030120210001_run-02")};
  const std::string one = pooled_json_with_threads(1, fit, heldout);
  ASSERT_NE(one.find("\"stderr\""), std::string::npos) << "no finding with standard errors: nothing compared";
  ASSERT_NE(one.find("\"cv_score\""), std::string::npos) << "no term search: nothing compared";
  // Several runs: what differed came and went with the heap's layout.
  for (int run = 0; run < 3; ++run)
    EXPECT_EQ(pooled_json_with_threads(2, fit, heldout), one) << "2 threads, run " << run;
}

}  // namespace
}  // namespace odotune::diagnose

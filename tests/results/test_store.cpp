#include <filesystem>

#include <gtest/gtest.h>

#include "results/store.h"

namespace odotune::results {
namespace {

struct TempPath {
  std::filesystem::path p = std::filesystem::temp_directory_path() /
                            ("odotune_store_" + std::to_string(::getpid()) + "_" + std::to_string(std::rand()) +
                             ".sqlite");
  ~TempPath() {
    for (const char* s : {"", "-wal", "-shm"}) std::filesystem::remove(p.string() + s);
  }
};

ExperimentInfo info(const std::string& text) {
  return {"study", text, experiment_hash(text), "0.1.0", "/experiments/study.yaml"};
}

RunRecord record(const std::string& model, int mode, std::uint64_t seed) {
  RunRecord r;
  r.model = model;
  r.track = "track1";
  r.mode = mode;
  r.seed = seed;
  r.param_names = {"alpha1", "alpha2"};
  r.params = {0.1 / 3.0, 1e-300};
  r.best_fitness = 0.123456789012345678;
  r.baseline = {0.1, 0.09, 0.3};
  r.tuned = {0.05, 0.04, 0.2};
  r.evaluations = 7550;
  r.seconds = 0.25;
  r.diverged = 3;
  r.termination = "max_iterations";
  r.convergence = {{50, 0.9}, {100, 0.5 / 7.0}};
  return r;
}

TEST(ResultsStore, RunsRoundTripBitForBitAcrossReopen) {
  TempPath tmp;
  const RunRecord a = record("rq", 7, 1), b = record("gyro", 2, 9);
  {
    Store s(tmp.p, info("models: [rq]"));
    s.add(a);
    s.add(b);
  }
  Store s(tmp.p, info("models: [rq]"));
  EXPECT_EQ(s.finished_keys(), (std::set<std::string>{run_key(a), run_key(b)}));
  const auto runs = s.runs();
  ASSERT_EQ(runs.size(), 2u);
  const RunRecord& r = runs[0];
  EXPECT_EQ(r.model, "rq");
  EXPECT_EQ(r.params, a.params);
  EXPECT_EQ(r.param_names, a.param_names);
  EXPECT_EQ(r.best_fitness, a.best_fitness);
  EXPECT_EQ(r.tuned.rmse_m, a.tuned.rmse_m);
  EXPECT_EQ(r.diverged, 3);
  ASSERT_EQ(r.convergence.size(), 2u);
  EXPECT_EQ(r.convergence[1].best_fitness, a.convergence[1].best_fitness);
  EXPECT_EQ(runs[1].model, "gyro");
  EXPECT_EQ(s.experiment().text, "models: [rq]");
  EXPECT_EQ(s.experiment().code_version, "0.1.0");
  EXPECT_EQ(s.experiment().file, "/experiments/study.yaml");
}

TEST(ResultsStore, RefusesAnotherExperimentUnlessAllowed) {
  TempPath tmp;
  { Store s(tmp.p, info("models: [rq]")); }
  try {
    Store s(tmp.p, info("models: [alpha]"));
    FAIL() << "expected a refusal";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another experiment"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(tmp.p.string()), std::string::npos);
  }
  EXPECT_NO_THROW(Store(tmp.p, info("models: [alpha]"), true));
}

TEST(ResultsStore, RepeatingARunIsAnErrorAndLeavesTheStoreIntact) {
  TempPath tmp;
  Store s(tmp.p, info("x"));
  s.add(record("rq", 1, 1));
  EXPECT_THROW(s.add(record("rq", 1, 1)), std::runtime_error);
  EXPECT_EQ(s.runs().size(), 1u);
  s.add(record("rq", 1, 2));
  EXPECT_EQ(s.runs().size(), 2u);
}

TEST(ResultsStore, ReadOnlyOpenOfAMissingStoreNamesIt) {
  try {
    Store s(std::filesystem::path("/nonexistent/dir/s.sqlite"));
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/s.sqlite"), std::string::npos);
  }
}

TEST(ResultsStore, HashTellsFilesApart) {
  EXPECT_EQ(experiment_hash("a"), experiment_hash("a"));
  EXPECT_NE(experiment_hash("a"), experiment_hash("b"));
  EXPECT_EQ(experiment_hash("").size(), 16u);
}

}  // namespace
}  // namespace odotune::results

#include <sqlite3.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>

#include <odotune/results/store.h>

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

std::uint64_t store_bits(double v) { return std::bit_cast<std::uint64_t>(v); }

TEST(ResultsStore, ParamRangesRoundTripBitForBit) {
  TempPath tmp;
  RunRecord a = record("rl-ekf", 10, 1);
  a.param_ranges = {{0.1 / 3.0, 7.25, true}, {1e-300, std::numeric_limits<double>::infinity(), false}};
  RunRecord b = record("rl-ekf", 11, 1);  // not profiled: no ranges
  {
    Store s(tmp.p, info("models: [rl-ekf]"));
    s.add(a);
    s.add(b);
    RunRecord bad = record("rl-ekf", 11, 2);
    bad.param_ranges = {{0.5, 2.0, true}};  // one range for two parameters
    EXPECT_THROW(s.add(bad), std::invalid_argument);
  }
  const auto runs = Store(tmp.p).runs();
  ASSERT_EQ(runs.size(), 2u);
  ASSERT_EQ(runs[0].param_ranges.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(store_bits(runs[0].param_ranges[i].lo), store_bits(a.param_ranges[i].lo)) << i;
    EXPECT_EQ(store_bits(runs[0].param_ranges[i].hi), store_bits(a.param_ranges[i].hi)) << i;
    EXPECT_EQ(runs[0].param_ranges[i].determined, a.param_ranges[i].determined) << i;
  }
  EXPECT_TRUE(runs[1].param_ranges.empty());
}

// A store written before param_ranges existed (schema 1, its exact table):
// read as it is with empty ranges, and upgraded in place when a grid
// continues into it.
TEST(ResultsStore, AStoreWithoutRangesOpensReadsAndTakesNewRuns) {
  TempPath tmp;
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(tmp.p.c_str(), &db), SQLITE_OK);
    const std::string text = "models: [rl-ekf]";
    const std::string sql =
        "PRAGMA journal_mode=WAL;"
        "CREATE TABLE experiment (key TEXT PRIMARY KEY, value TEXT NOT NULL);"
        "CREATE TABLE runs ( id INTEGER PRIMARY KEY AUTOINCREMENT, key TEXT UNIQUE NOT NULL,"
        " model TEXT, track TEXT, heldout_track TEXT, mode INTEGER, seed INTEGER, solver TEXT,"
        " params TEXT, best_fitness REAL,"
        " baseline_rmse_m REAL, baseline_mae_m REAL, baseline_maxe_m REAL,"
        " tuned_rmse_m REAL, tuned_mae_m REAL, tuned_maxe_m REAL,"
        " evaluations INTEGER, seconds REAL, diverged INTEGER, termination TEXT, convergence TEXT);"
        "INSERT INTO experiment VALUES ('schema_version', '1'), ('name', 'study'), ('text', '" +
        text + "'), ('hash', '" + experiment_hash(text) +
        "'), ('code_version', '0.1.0'), ('file', '/experiments/study.yaml');"
        "INSERT INTO runs (key, model, track, heldout_track, mode, seed, solver, params, best_fitness,"
        " baseline_rmse_m, baseline_mae_m, baseline_maxe_m, tuned_rmse_m, tuned_mae_m, tuned_maxe_m,"
        " evaluations, seconds, diverged, termination, convergence) VALUES ('rl-ekf|track1||10|1|pso', 'rl-ekf',"
        " 'track1', '', 10, 1, 'pso', '[[\"q_x\",2.5]]', 0.5, 0.1, 0.09, 0.3, 0.05, 0.04, 0.2, 32, 1.5, 0,"
        " 'budget', '[[8,0.7],[32,0.5]]');";
    char* err = nullptr;
    ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err), SQLITE_OK) << (err ? err : "");
    sqlite3_close(db);
  }
  {
    const auto old = Store(tmp.p).runs();  // read-only: not upgraded
    ASSERT_EQ(old.size(), 1u);
    EXPECT_EQ(old[0].param_names, std::vector<std::string>{"q_x"});
    EXPECT_EQ(old[0].params, std::vector<double>{2.5});
    EXPECT_TRUE(old[0].param_ranges.empty());
    EXPECT_EQ(old[0].convergence.size(), 2u);
  }
  RunRecord a = record("rl-ekf", 11, 1);
  a.param_ranges = {{0.5, 2.0, true}, {0.25, 4.0, false}};
  {
    Store s(tmp.p, info("models: [rl-ekf]"));
    EXPECT_EQ(s.finished_keys().size(), 1u);
    s.add(a);
  }
  Store s(tmp.p, info("models: [rl-ekf]"));  // opening an upgraded store again changes nothing
  const auto runs = s.runs();
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_TRUE(runs[0].param_ranges.empty());
  EXPECT_EQ(runs[0].tuned.rmse_m, 0.05);
  ASSERT_EQ(runs[1].param_ranges.size(), 2u);
  EXPECT_EQ(runs[1].param_ranges[1].hi, 4.0);
  EXPECT_FALSE(runs[1].param_ranges[1].determined);
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
// A diverged run's held-out metrics are NaN; SQLite keeps a bound NaN as
// NULL, which must read back as NaN, not as 0 m.
TEST(ResultsStore, NanMetricsReadBackAsNan) {
  TempPath tmp;
  RunRecord a = record("rl-ukf", 8, 1);
  a.tuned = {std::nan(""), std::nan(""), std::nan("")};
  {
    Store s(tmp.p, info("models: [rl-ukf]"));
    s.add(a);
  }
  const auto runs = Store(tmp.p).runs();
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_TRUE(std::isnan(runs[0].tuned.rmse_m));
  EXPECT_TRUE(std::isnan(runs[0].tuned.maxe_m));
  EXPECT_EQ(runs[0].baseline.rmse_m, a.baseline.rmse_m);
}

}  // namespace odotune::results

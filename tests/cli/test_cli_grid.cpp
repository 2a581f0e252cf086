// The overnight grid: killed with SIGKILL at random moments and restarted, it
// ends with exactly the rows of an uninterrupted run; a store from another
// experiment is refused.
#include <algorithm>
#include <fstream>
#include <map>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <odotune/results/store.h>

#include "support/cli_runner.h"
#include "support/store_rows.h"

namespace odotune::cli {
namespace {

using testing_support::reference_track;
using testing_support::run_cli;
using testing_support::store_rows;
using testing_support::TempDir;

std::string experiment_text(int iterations) {
  return fmt::format("format: odotune-experiment/1\nname: kill-test\nmodels: [rq, gyro]\n"
                     "tracks: [{}, {}]\nmodes: [1, 6]\nseeds: [1, 2, 3]\nsolver: pso\n"
                     "budget: {{particles: 16, iterations: {}}}\nleave_one_out: true\nstore: s.sqlite\n",
                     reference_track(2), reference_track(4), iterations);
}

TEST(CliGrid, ResumesAfterSigkillToTheSameRowsAsAnUninterruptedRun) {
  TempDir ref_dir, kill_dir;
  for (const auto* d : {&ref_dir, &kill_dir}) std::ofstream(*d / "e.yaml") << experiment_text(25);
  const auto ref = run_cli("grid " + (ref_dir / "e.yaml").string() + " --threads 2");
  ASSERT_EQ(ref.exit_code, 0) << ref.err;
  const auto expected = store_rows(ref_dir / "s.sqlite");
  ASSERT_EQ(expected.size(), 2u * 2u * 2u * 3u * 2u);  // per-track + leave-one-out cells

  // Kill at seeded random moments until a restart finishes the job.
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> delay(0.02, 0.4);
  int kills = 0;
  for (int attempt = 0; attempt < 40; ++attempt) {
    const std::string cmd = fmt::format("CI=1 timeout -s KILL {:.3f} {} grid {} --threads {} >/dev/null 2>&1",
                                        delay(rng), ODOTUNE_BINARY, (kill_dir / "e.yaml").string(),
                                        1 + attempt % 2);
    const int status = std::system(cmd.c_str());
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) break;
    ++kills;
  }
  EXPECT_GT(kills, 0) << "the job was never killed; the test proves nothing";
  const auto finish = run_cli("grid " + (kill_dir / "e.yaml").string());
  ASSERT_EQ(finish.exit_code, 0) << finish.err;
  EXPECT_EQ(store_rows(kill_dir / "s.sqlite"), expected);
}

TEST(CliGrid, RefusesAStoreFromAnotherExperiment) {
  TempDir dir;
  std::ofstream(dir / "a.yaml") << experiment_text(2);
  std::ofstream(dir / "b.yaml") << experiment_text(3);
  ASSERT_EQ(run_cli("grid " + (dir / "a.yaml").string()).exit_code, 0);
  const auto r = run_cli("grid " + (dir / "b.yaml").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("another experiment"), std::string::npos) << r.err;
  EXPECT_EQ(run_cli("grid " + (dir / "b.yaml").string() + " --allow-other-experiment").exit_code, 0);
}

TEST(CliGrid, CreatesTheStoresFolder) {
  TempDir dir;
  std::ofstream(dir / "e.yaml") << experiment_text(1);
  const auto r = run_cli("grid " + (dir / "e.yaml").string() + " --store " +
                         (dir / "new/sub/s.sqlite").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(results::Store(dir / "new/sub/s.sqlite").runs().size(), 48u);
}

TEST(CliGrid, BadExperimentFileNamesFileAndLine) {
  TempDir dir;
  std::ofstream(dir / "bad.yaml") << "format: odotune-experiment/1\nmodels: [rq]\ntracks: ["
                                  << reference_track(1) << "]\nmodes: [1, 10]\nseeds: [1]\n";
  const auto r = run_cli("grid " + (dir / "bad.yaml").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("bad.yaml:4:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("mode 10 is out of range, expected 1..9"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace odotune::cli

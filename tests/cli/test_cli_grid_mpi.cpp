// `mpirun -np 2 odotune grid` on this machine: the two ranks' store holds
// exactly the rows of a one-process run; a failure on any rank is told once and
// ends the job; a job stopped at random moments resumes to the same rows.
// (Only in a build with -DODOTUNE_WITH_MPI=ON; the default build has no MPI.)
#if defined(ODOTUNE_WITH_MPI) && ODOTUNE_WITH_MPI

#include <sys/wait.h>

#include <chrono>
#include <fstream>
#include <random>
#include <regex>
#include <thread>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support/cli_runner.h"
#include "support/store_rows.h"

namespace odotune::cli {
namespace {

using testing_support::CliResult;
using testing_support::reference_track;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::store_rows;
using testing_support::TempDir;

// 2 models × 2 tracks × 2 modes × `seeds` seeds, plus the leave-one-out
// cells (tuned on one track, scored on the other): 16 runs per seed, PSO with
// 12 particles; 32 runs of 12 iterations take ~0.3 s.
std::string mpi_experiment_text(int iterations, int seeds = 2) {
  return fmt::format("format: odotune-experiment/1\nname: mpi-test\nmodels: [rq, alpha]\n"
                     "tracks: [{}, {}]\nmodes: [1, 7]\nseeds: {{first: 1, count: {}}}\nsolver: pso\n"
                     "budget: {{particles: 12, iterations: {}}}\nleave_one_out: true\nstore: s.sqlite\n",
                     reference_track(1), reference_track(3), seeds, iterations);
}
constexpr std::size_t kRuns = 2 * 2 * 2 * 2 * 2;

// `mpirun -np N odotune ARGS` with CI=1, bounded in time; allowed as root (CI).
// (`program` is odotune unless given.)
std::string mpirun_command(int ranks, const std::string& args, const std::string& program = ODOTUNE_BINARY) {
  return fmt::format("CI=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
                     "timeout -s KILL 240 {} -np {} --oversubscribe {} {}",
                     ODOTUNE_MPIEXEC, ranks, program, args);
}

CliResult run_mpi(int ranks, const std::string& args, const std::string& program = ODOTUNE_BINARY) {
  TempDir io("mpi-io");
  const int status = std::system(
      (mpirun_command(ranks, args, program) + " >" + (io / "out").string() + " 2>" + (io / "err").string())
          .c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(io / "out");
  r.err = slurp(io / "err");
  return r;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(CliGridMpi, TwoRanksWriteExactlyTheRowsOfOneProcess) {
  TempDir dir;
  std::ofstream(dir / "e.yaml") << mpi_experiment_text(12);
  const auto one = run_cli("grid " + (dir / "e.yaml").string() + " --store " + (dir / "one.sqlite").string());
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const auto expected = store_rows(dir / "one.sqlite");
  ASSERT_EQ(expected.size(), kRuns);

  const auto two = run_mpi(2, "grid " + (dir / "e.yaml").string() + " --threads 1 --store " +
                                  (dir / "two.sqlite").string());
  ASSERT_EQ(two.exit_code, 0) << two.out << two.err;
  EXPECT_EQ(count(two.out, "runs in the experiment"), 1u) << "only rank 0 reports:\n" << two.out;
  EXPECT_NE(two.out.find(fmt::format("{} run now (on 2 MPI ranks)", kRuns)), std::string::npos) << two.out;
  EXPECT_EQ(store_rows(dir / "two.sqlite"), expected);

  // Run again: everything is stored, nothing runs twice.
  const auto again = run_mpi(2,
                             "grid " + (dir / "e.yaml").string() + " --store " + (dir / "two.sqlite").string());
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find(fmt::format("{} already stored, 0 run now", kRuns)), std::string::npos) << again.out;
}

// True once process `pid` has ended (a zombie has ended too: it writes nothing).
bool ended(const std::string& pid) {
  std::ifstream stat("/proc/" + pid + "/stat");  // "PID (NAME) STATE ..."
  std::string same_pid, name, state;
  if (!(stat >> same_pid >> name >> state)) return true;
  return state == "Z";
}

TEST(CliGridMpi, StoppedOrKilledAtRandomMomentsResumesToTheRowsOfOneProcess) {
  TempDir ref_dir, dir;
  // Long enough (~2 s on 2 ranks) to be stopped a few times at random moments.
  for (const auto* d : {&ref_dir, &dir}) std::ofstream(*d / "e.yaml") << mpi_experiment_text(400, 4);
  const auto ref = run_cli("grid " + (ref_dir / "e.yaml").string());
  ASSERT_EQ(ref.exit_code, 0) << ref.err;
  const auto expected = store_rows(ref_dir / "s.sqlite");
  ASSERT_EQ(expected.size(), 2 * kRuns);

  // Each rank notes its pid, so that no rank of a killed job is still
  // running (and writing) when the next job starts.
  std::ofstream(dir / "rank.sh") << fmt::format("#!/bin/sh\necho $$ >>{}/pids\nexec {} \"$@\"\n",
                                                dir.path().string(), ODOTUNE_BINARY);
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> delay(0.3, 1.0);
  int stopped = 0;
  for (int attempt = 0; attempt < 8 && stopped < 4; ++attempt) {
    // SIGTERM to mpirun (as Ctrl-C or scancel): the ranks stop cleanly.
    // SIGKILL: mpirun and the ranks die wherever they are.
    const std::string cmd = fmt::format(
        "CI=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 timeout -s {} {:.3f} {} -np 2 "
        "--oversubscribe sh {} grid {} --threads 1 >/dev/null 2>&1",
        attempt % 2 ? "KILL" : "TERM", delay(rng), ODOTUNE_MPIEXEC, (dir / "rank.sh").string(),
        (dir / "e.yaml").string());
    const int status = std::system(cmd.c_str());
    std::ifstream pids(dir / "pids");
    for (std::string pid; pids >> pid;)
      for (int wait_ms = 0; !ended(pid); wait_ms += 50) {
        ASSERT_LT(wait_ms, 30000) << "rank " << pid << " outlived its job";
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) break;
    ++stopped;
  }
  RecordProperty("stopped", stopped);
  EXPECT_GT(stopped, 0) << "the job was never stopped; the test proves nothing";
  const auto finish = run_mpi(2, "grid " + (dir / "e.yaml").string());
  ASSERT_EQ(finish.exit_code, 0) << finish.err;
  EXPECT_EQ(store_rows(dir / "s.sqlite"), expected);
}

TEST(CliGridMpi, AFailureOnAnyRankIsToldOnceAndEndsTheJob) {
  TempDir dir;
  // A bad experiment file: every rank finds it, rank 0 alone says so.
  std::ofstream(dir / "bad.yaml") << "format: odotune-experiment/1\nmodels: [rq]\ntracks: ["
                                  << reference_track(1) << "]\nmodes: [1, 10]\nseeds: [1]\n";
  const auto bad = run_mpi(2, "grid " + (dir / "bad.yaml").string());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_EQ(count(bad.err, "bad.yaml:4:"), 1u) << bad.err;

  // A store of another experiment: only rank 0 opens it, the job still ends.
  std::ofstream(dir / "a.yaml") << mpi_experiment_text(1);
  std::ofstream(dir / "b.yaml") << mpi_experiment_text(2);
  ASSERT_EQ(run_cli("grid " + (dir / "a.yaml").string()).exit_code, 0);
  const auto other = run_mpi(2, "grid " + (dir / "b.yaml").string());
  EXPECT_NE(other.exit_code, 0);
  EXPECT_EQ(count(other.err, "another experiment"), 1u) << other.err;

  // A run that fails (here every run: an unknown solver) stops every rank.
  std::ofstream(dir / "bogus.yaml") << std::regex_replace(mpi_experiment_text(1), std::regex("solver: pso"),
                                                          "solver: nlopt:LN_BOGUS");
  const auto bogus = run_mpi(2, "grid " + (dir / "bogus.yaml").string() + " --store " +
                                    (dir / "bogus.sqlite").string());
  EXPECT_NE(bogus.exit_code, 0);
  EXPECT_EQ(count(bogus.err, "unknown algorithm 'LN_BOGUS'"), 1u) << bogus.err;
  // No run finished: the store this command created is not left behind.
  EXPECT_FALSE(std::filesystem::exists(dir / "bogus.sqlite"));

  // Rank 1 reads another experiment file than rank 0 (as on a node whose
  // copy differs): refused before any run.
  TempDir node("node");
  std::ofstream(node / "c.yaml") << mpi_experiment_text(1);
  std::ofstream(node / "d.yaml") << mpi_experiment_text(1) << "# changed on one node\n";
  std::ofstream(node / "by_rank.sh") << fmt::format(
      "#!/bin/sh\nif [ \"$OMPI_COMM_WORLD_RANK\" = 1 ]; then exec {0} grid {1}/d.yaml; fi\n"
      "exec {0} grid {1}/c.yaml\n",
      ODOTUNE_BINARY, node.path().string());
  const auto differ = run_mpi(2, (node / "by_rank.sh").string(), "sh");
  EXPECT_NE(differ.exit_code, 0);
  EXPECT_EQ(count(differ.err, "rank 1: it reads another experiment than rank 0"), 1u) << differ.err;
  EXPECT_FALSE(std::filesystem::exists(node / "s.sqlite"));  // no run: no store left behind
}

}  // namespace
}  // namespace odotune::cli

#endif  // ODOTUNE_WITH_MPI

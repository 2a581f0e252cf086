// eval and tune with --rl-params on tracks: robot_localization's EKF replayed
// from a track's odometry, gyro and fixes and scored against its ground
// truth, end to end through the binary; the tuned file replays to the figures
// the tune reported.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include <odotune/rlnode/params.h>
#include <odotune/tracks/track_io.h>

#include "support/cli_runner.h"
#include "support/rl_team_file.h"
#include "support/synthetic_track.h"
#include "support/temp_dir.h"

using odotune::testing_support::number_after;
using odotune::testing_support::run_cli;
using odotune::testing_support::slurp;
using odotune::testing_support::TempDir;

namespace {

// Two drives of a_s and b_s seconds. The tunes take shorter ones, each
// evaluation replaying every track: 45 s leaves one outage window of 10 s
// after the 30 s of GPS before the first.
struct Drive {
  TempDir dir{"cli-rl-track"};
  std::string params = (dir.path() / "user.yaml").string();
  std::string a = (dir.path() / "a.csv").string(), b = (dir.path() / "b.csv").string();
  explicit Drive(double a_s = 60.0, double b_s = 50.0) {
    std::ofstream(params) << odotune::testing_support::kRlTeamFile << odotune::testing_support::kRlGyroInput;
    odotune::tracks::write_track(odotune::testing_support::synthetic_track(11, a_s), a);
    odotune::tracks::write_track(odotune::testing_support::synthetic_track(12, b_s), b);
  }
};

const std::string kShort = " --fix-sigma-m 0.06 --outage 10 --outage-every 5";

}  // namespace

TEST(CliRlTrack, EvalScoresAgainstGroundTruthAndWritesThePathOnTheTracksClock) {
  Drive d;
  const auto tum = d.dir.path() / "a.tum", json_file = d.dir.path() / "a.json";
  const auto r = run_cli("eval --rl-params " + d.params + " --track " + d.a +
                         " --fix-sigma-m 0.06 --outages 10 --outage-every 5 --trajectory-out " + tum.string() +
                         " --json " + json_file.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double run = number_after(r.out, "every fix fused RMSE");
  const double outages = number_after(r.out, R"(simulated fix outages RMSE)");
  EXPECT_GT(run, 0.0) << r.out;
  EXPECT_LT(run, 0.15) << r.out;
  EXPECT_GT(outages, run) << r.out;
  EXPECT_NE(r.out.find("held-out fixes"), std::string::npos) << r.out;
  const std::string t = slurp(tum);
  // 20 Hz from the first fix at 1 s to 60 s.
  EXPECT_GT(std::count(t.begin(), t.end(), '\n'), 1100);
  EXPECT_NE(t.find("\n1.0"), std::string::npos) << t.substr(0, 300);
  EXPECT_EQ(t.find("\n0."), std::string::npos);
  EXPECT_NE(slurp(json_file).find("\"truth\""), std::string::npos);
}

TEST(CliRlTrack, TunedFileReplaysToTheReportedFigures) {
  const Drive d(45.0, 42.0);
  const auto out = d.dir.path() / "tuned.yaml";
  const auto r = run_cli("tune --rl-params " + d.params + " --track " + d.a + " --track " + d.b + kShort +
                         " --space blocks --no-input-covariances --grid=-1,1 --config-out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("against ground truth on the tuned tracks"), std::string::npos) << r.out;
  const std::string text = slurp(out);
  EXPECT_NE(text.find("# Tracks: "), std::string::npos) << text;
  EXPECT_EQ(odotune::rlnode::read_rl_params(out).sensors.size(), 3u);
  const double tuned_a = number_after(r.out, R"(a\.csv: fixes fused [0-9.]+ m ->)");
  const auto e = run_cli("eval --rl-params " + out.string() + " --track " + d.a +
                         " --fix-sigma-m 0.06 --outages 10 --outage-every 5");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NEAR(number_after(e.out, "every fix fused RMSE"), tuned_a, 0.0005) << r.out << "\n" << e.out;
}

TEST(CliRlTrack, RefusesWhatDoesNotApplyInOneLine) {
  Drive d;
  const std::string src = "--rl-params " + d.params + " --track " + d.a;
  for (const std::string& args :
       {"eval " + src + " --fix-sigma-m 0.06 --tf imu=0,0,0,0,0,0",
        "tune " + src + " --fix-sigma-m 0.06 --until 30", "eval " + src + " --twist-variance 0.001",
        "eval --track " + d.a + " --fix-sigma-m 0.06", "eval " + src,
        "tune " + src + " --fix-sigma-m 10 --outage 10 --outage-every 5 --grid=-1,1 --subtract-fix-variance"}) {
    const auto r = run_cli(args);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\n" << r.err;
  }
  EXPECT_NE(run_cli("eval " + src).err.find("--fix-sigma-m"), std::string::npos);
  EXPECT_NE(run_cli("tune " + src + " --fix-sigma-m 0.06 --until 30").err.find("--until"), std::string::npos);
  // Variances far above the fixes' scatter leave no error once taken out.
  EXPECT_NE(run_cli("tune " + src + " --fix-sigma-m 10 --outage 10 --outage-every 5 --subtract-fix-variance")
                .err.find("exceed the file's squared error"),
            std::string::npos);
}

// 30 s leave no outage window after the 30 s of GPS before the first: eval
// says n/a and tune refuses for that reason, neither calls the file's filter
// diverged.
TEST(CliRlTrack, ADriveTooShortForAnOutageIsNotCalledDiverged) {
  const Drive d(30.0);
  const auto e = run_cli("eval --rl-params " + d.params + " --track " + d.a +
                         " --fix-sigma-m 0.06 --outages 10 --outage-every 5");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NE(e.out.find("outages RMSE n/a"), std::string::npos) << e.out;
  EXPECT_EQ(e.out.find("diverged"), std::string::npos) << e.out;
  const auto t = run_cli("tune --rl-params " + d.params + " --track " + d.a + kShort + " --grid=0");
  EXPECT_NE(t.exit_code, 0);
  EXPECT_NE(t.err.find("no fix is scored before the tuning span ends"), std::string::npos) << t.err;
  EXPECT_EQ(std::count(t.err.begin(), t.err.end(), '\n'), 1) << t.err;
}

TEST(CliRlTrack, ATuneWithTheFixesVarianceTakenOutSaysSoInTheFile) {
  const Drive d(45.0);
  const auto out = d.dir.path() / "tuned.yaml", json_file = d.dir.path() / "tune.json";
  const auto r = run_cli(
      "tune --rl-params " + d.params + " --track " + d.a + kShort +
      " --space blocks --no-input-covariances --grid=-1,1 --subtract-fix-variance --config-out " +
      out.string() + " --json " + json_file.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(slurp(out).find("fitness both (the fixes' own variance taken out)"), std::string::npos)
      << slurp(out);
  EXPECT_NE(slurp(json_file).find("\"subtract_fix_variance\": true"), std::string::npos);
}

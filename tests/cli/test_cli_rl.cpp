// eval and tune with --rl-params: robot_localization's EKF from the Husky bag
// and the user's parameter file (husky_ekf.yaml), end to end through the
// binary; the tuned file replays to the figures the tune reported.
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include <odotune/rlnode/params.h>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

using odotune::testing_support::number_after;
using odotune::testing_support::run_cli;
using odotune::testing_support::slurp;
using odotune::testing_support::TempDir;

namespace {

const std::string kBags = std::string(ODOTUNE_SHARED_DIR) + "/data/real/robot_localization_bags";
const std::string kSource =
    "--rl-params " + kBags + "/husky_ekf.yaml --bag " + kBags +
    "/ros2/test1.mcap --tf imu_link=0,-0.3,0.52,1.5707963267948966,0,-1.5707963267948966 "
    "--gps-heading-fit 60";

}  // namespace

TEST(CliRl, EvalReplaysTheUsersFileAndScoresTheSecondHalf) {
  TempDir dir("cli-rl-eval");
  const auto json_file = dir.path() / "e.json", tum = dir.path() / "e.tum";
  const auto r = run_cli("eval " + kSource + " --from 197.65 --json " + json_file.string() +
                         " --trajectory-out " + tum.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("GPS heading fitted"), std::string::npos) << r.out;
  // robot_localization's defaults on the held-out half: the outage error is
  // metres, the every-5th-fix error under a metre (docs/husky.md).
  const double outage = number_after(r.out, "GPS outage RMSE");
  const double fifth = number_after(r.out, "every 5th fix held out: RMSE");
  EXPECT_GT(outage, 5.0) << r.out;
  EXPECT_GT(fifth, 0.1) << r.out;
  EXPECT_LT(fifth, 1.5) << r.out;
  EXPECT_NE(slurp(json_file).find("\"every_fifth_fix\""), std::string::npos);
  const std::string t = slurp(tum);
  EXPECT_GT(std::count(t.begin(), t.end(), '\n'), 10000);  // 30 Hz over 395 s
}

TEST(CliRl, RefusesFlagsThatBelongToTracks) {
  const auto a = run_cli("eval " + kSource + " --track " + odotune::testing_support::reference_track(1));
  EXPECT_NE(a.exit_code, 0);
  EXPECT_NE(a.err.find("--rl-params"), std::string::npos) << a.err;
  const auto b = run_cli("tune " + kSource + " --model alpha");
  EXPECT_NE(b.exit_code, 0);
  EXPECT_NE(b.err.find("--model does not apply to --rl-params"), std::string::npos) << b.err;
  const auto c = run_cli("eval --rl-params " + kBags + "/husky_ekf.yaml --bag " + kBags +
                         "/ros2/test1.mcap --tf imu_link=1,2");
  EXPECT_NE(c.exit_code, 0);
  EXPECT_NE(c.err.find("--tf imu_link=1,2"), std::string::npos) << c.err;
  EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << c.err;
}

// A small tune on the first 100 s, two starts: the written file is the user's
// file with the tuned noise and the start of lowest tuning fitness, it names
// what the recording did not determine, it reads back, and replayed as
// written it gives the held-out figure the tune printed; each start's file is
// written too.
TEST(CliRl, TunedFileReplaysToTheReportedFigures) {
  TempDir dir("cli-rl-tune");
  const auto out = dir.path() / "ekf.yaml", ros1 = dir.path() / "ekf-ros1.yaml", starts = dir.path() / "starts";
  const auto r = run_cli("tune " + kSource +
                         " --until 100 --fitness both --space blocks --no-input-covariances --grid=-1,1 "
                         "--refine 0.5 --particles 4 --iterations 2 --seed 3 --starts 2 --starts-out " +
                         starts.string() + " --config-out " + out.string() + " --config-out-ros1 " +
                         ros1.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(out);
  EXPECT_NE(text.find("# Tuned by odotune"), std::string::npos);
  EXPECT_NE(text.find("of 2 starts, seeds 3-4"), std::string::npos) << text;
  EXPECT_NE(text.find("# Not determined by this recording"), std::string::npos) << text;
  EXPECT_NE(r.out.find("not determined by this recording"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("<- written"), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::exists(starts / "ekf-seed3.yaml"));
  EXPECT_TRUE(std::filesystem::exists(starts / "ekf-seed4.yaml"));
  EXPECT_NE(text.find("navsat_transform"), std::string::npos);  // the user's other section kept
  const auto p2 = odotune::rlnode::read_rl_params(out);
  const auto p1 = odotune::rlnode::read_rl_params(ros1);
  EXPECT_TRUE(p2.ros2);
  EXPECT_FALSE(p1.ros2);
  EXPECT_EQ(p1.process_noise_covariance, p2.process_noise_covariance);
  EXPECT_EQ(p2.sensors.size(), 3u);

  const double tuned_outage = number_after(r.out, R"(GPS outage:\s+[0-9.]+ ->)");
  const auto e = run_cli("eval --rl-params " + out.string() + " --bag " + kBags +
                         "/ros2/test1.mcap --tf imu_link=0,-0.3,0.52,1.5707963267948966,0,-1.5707963267948966 "
                         "--gps-heading-fit 60 --from 100");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const double replayed = number_after(e.out, "GPS outage RMSE");
  EXPECT_NEAR(replayed, tuned_outage, 0.001) << r.out << "\n" << e.out;
}

// The reverse fold: tuned on the recording after --from (the bag cut there),
// judged before it (the GPS fused for the first 60 s, then an outage); the
// written file replays to the judged outage figure. --until and --from
// together are refused.
TEST(CliRl, TuneFromJudgesTheSpanBefore) {
  TempDir dir("cli-rl-from");
  const auto out = dir.path() / "ekf.yaml", json_file = dir.path() / "t.json";
  const auto r = run_cli("tune " + kSource +
                         " --from 300 --space blocks --no-input-covariances --outage 30 --grid=-1,1 --refine 0 "
                         "--config-out " +
                         out.string() + " --json " + json_file.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("tuned on 300.0-395.3 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("judged on 0.0-300.0 s"), std::string::npos) << r.out;
  const double judged = number_after(r.out, R"(GPS outage:\s+[0-9.]+ ->)");
  const auto e = run_cli("eval --rl-params " + out.string() + " --bag " + kBags +
                         "/ros2/test1.mcap --tf imu_link=0,-0.3,0.52,1.5707963267948966,0,-1.5707963267948966 "
                         "--gps-heading-fit 60 --from 60 --until 300");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NEAR(number_after(e.out, "GPS outage RMSE"), judged, 0.001) << r.out << "\n" << e.out;
  EXPECT_NE(slurp(json_file).find("\"held_out\""), std::string::npos);

  const auto both = run_cli("tune " + kSource + " --until 100 --from 300");
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.err.find("--until and --from"), std::string::npos) << both.err;
  EXPECT_EQ(std::count(both.err.begin(), both.err.end(), '\n'), 1) << both.err;
  const auto grid = run_cli("tune " + kSource + " --until 100 --grid=-1,x");
  EXPECT_NE(grid.exit_code, 0);
  EXPECT_NE(grid.err.find("--grid -1,x"), std::string::npos) << grid.err;
}

// The Husky's file run as ukf_node (--filter ukf): the tune says so, writes
// ukf_node's alpha, kappa and beta so that the file says it is the UKF's by
// itself, and the file replays to the judged figure it printed. With the
// outages in the fitness the file's own UKF diverges (its unmeasured heading),
// which the tune says in one line; --filter ekf with a UKF file is refused.
TEST(CliRl, UkfTuneWritesAUkfFileThatReplaysToItsFigures) {
  TempDir dir("cli-rl-ukf");
  const auto out = dir.path() / "ukf.yaml";
  const auto r = run_cli(
      "tune " + kSource +
      " --filter ukf --until 30 --fitness heldout-fixes --space blocks --no-input-covariances "
      "--ukf-constants --grid=-1,1 --refine 0 --seed 3 --config-out " +
      out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("robot_localization UKF (husky_ekf.yaml)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ukf_alpha ×"), std::string::npos) << r.out;  // searched, in the profile
  EXPECT_NE(r.out.find("ukf_n_plus_kappa ×"), std::string::npos) << r.out;
  const auto p = odotune::rlnode::read_rl_params(out);
  EXPECT_EQ(p.filter, odotune::filters::rl::RlFilterType::ukf);
  EXPECT_GT(p.ukf.alpha, 0.0);
  const double judged = number_after(r.out, R"(every 5th fix held out:\s+[0-9.]+ ->)");
  const std::string source =
      " --bag " + kBags +
      "/ros2/test1.mcap --tf imu_link=0,-0.3,0.52,1.5707963267948966,0,-1.5707963267948966 "
      "--gps-heading-fit 60 --from 30";
  const auto e = run_cli("eval --rl-params " + out.string() + source);
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NE(e.out.find("robot_localization UKF"), std::string::npos) << e.out;
  EXPECT_NEAR(number_after(e.out, "every 5th fix held out: RMSE"), judged, 0.001) << r.out << "\n" << e.out;

  const auto both = run_cli("tune " + kSource + " --filter ukf --until 100 --fitness both");
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.err.find("ukf_node diverges on this recording"), std::string::npos) << both.err;
  EXPECT_EQ(std::count(both.err.begin(), both.err.end(), '\n'), 1) << both.err;
  const auto ekf = run_cli("eval --rl-params " + out.string() + " --filter ekf" + source);
  EXPECT_NE(ekf.exit_code, 0);
  EXPECT_NE(ekf.err.find("alpha is read by ukf_node only"), std::string::npos) << ekf.err;
  const auto constants = run_cli("tune " + kSource + " --until 100 --ukf-constants");
  EXPECT_NE(constants.exit_code, 0);
  EXPECT_NE(constants.err.find("alpha, kappa and beta are ukf_node's"), std::string::npos) << constants.err;
  EXPECT_EQ(std::count(constants.err.begin(), constants.err.end(), '\n'), 1) << constants.err;
}

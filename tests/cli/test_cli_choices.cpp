// Flags whose value is one of a type's names (odotune/cli/choices.h): --help
// lists the names, a wrong value is refused in one line naming the flag, the
// value and the valid names, and nothing is written. And the flags a run does
// not take, refused by their help group (odotune/cli/rl_output.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace odotune::cli {
namespace {

using testing_support::reference_track;
using testing_support::run_cli;
using testing_support::TempDir;

const std::string kChoicesBags = std::string(ODOTUNE_SHARED_DIR) + "/data/real/robot_localization_bags";
const std::string kChoicesParams = kChoicesBags + "/husky_ekf.yaml";
const std::string kChoicesBag = kChoicesBags + "/ros2/test1.mcap";

std::size_t choice_error_lines(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

struct WrongChoice {
  std::string args;      // the command line, with the wrong value
  std::string expected;  // the refusal: flag, value and valid names
};

TEST(CliChoices, AWrongChoiceIsRefusedInOneLineNamingTheValidNames) {
  TempDir tmp("cli-choices");
  const std::string json_out = (tmp / "out.json").string();
  const std::string track = reference_track(1);
  const std::vector<WrongChoice> cases = {
      {"tune --track " + track + " --model rqq",
       "--model 'rqq': expected rq, alpha, gyro, pf-calib, adaptive-pf-calib, ukf, rl-ekf or rl-ukf"},
      {"tune --track " + track + " --model pf-calib --resampler sorted",
       "--resampler 'sorted': expected multinomial, stratified, systematic or residual"},
      {"tune --track " + track + " --model pf-calib --policy often",
       "--policy 'often': expected every, neff or max"},
      {"tune --rl-params " + kChoicesParams + " --bag " + kChoicesBag + " --fitness best",
       "--fitness 'best': expected heldout-fixes, outage, both, innovation-nll, nis, whiteness or heldout-nll"},
      {"tune --rl-params " + kChoicesParams + " --bag " + kChoicesBag + " --space block",
       "--space 'block': expected diagonal or blocks"},
      {"tune --rl-params " + kChoicesParams + " --bag " + kChoicesBag + " --format ros3",
       "--format 'ros3': expected ros2 or ros1"},
      {"tune --rl-params " + kChoicesParams + " --bag " + kChoicesBag + " --filter pf",
       "--filter 'pf': expected ekf or ukf"},
      {"eval --rl-params " + kChoicesParams + " --track " + track + " --odometry wheel",
       "--odometry 'wheel': expected wheels, twist or commands"},
      {"calibrate --track " + track + " --method kalman",
       "--method 'kalman': expected adaptive-pf, pf, dkf, online-pose, batch-pose, batch-velocity or none"},
      {"calibrate --track " + track + " --method online-pose --start lost",
       "--start 'lost': expected fixes or known"},
      {"calibrate --track " + track + " --method pf --pf-evolution fast",
       "--pf-evolution 'fast': expected paper or evidence"},
      {"export nothing.sqlite --format yaml --out " + (tmp / "x.yaml").string(),
       "--format 'yaml': expected odotune or robot_localization"},
      {"import rosbag nothing.bag -o " + (tmp / "x.csv").string() + " --stamps sent",
       "--stamps 'sent': expected header or receive"},
  };
  for (const WrongChoice& c : cases) {
    const bool exports = c.args.rfind("export", 0) == 0 || c.args.rfind("import", 0) == 0;
    const auto r = run_cli(c.args + (exports ? "" : " --json " + json_out));
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_EQ(choice_error_lines(r.err), 1u) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << ": " << r.err;
    EXPECT_EQ(tmp.entries(), 0u) << c.args;  // nothing written
  }
}

TEST(CliChoices, HelpListsTheValidNames) {
  struct Listed {
    std::string command, option;
  };
  const std::vector<Listed> listed = {
      {"tune", "--model TEXT:{rq,alpha,gyro,pf-calib,adaptive-pf-calib,ukf,rl-ekf,rl-ukf}"},
      {"tune", "--resampler TEXT:{multinomial,stratified,systematic,residual}"},
      {"tune", "--policy TEXT:{every,neff,max}"},
      {"tune", "--fitness TEXT:{heldout-fixes,outage,both,innovation-nll,nis,whiteness,heldout-nll}"},
      {"tune", "--space TEXT:{diagonal,blocks}"},
      {"tune", "--format TEXT:{ros2,ros1}"},
      {"tune", "--filter TEXT:{ekf,ukf}"},
      {"eval", "--odometry TEXT:{wheels,twist,commands}"},
      {"calibrate", "--method TEXT:{adaptive-pf,pf,dkf,online-pose,batch-pose,batch-velocity,none}"},
      {"calibrate", "--start TEXT:{fixes,known}"},
      {"export", "--format TEXT:{odotune,robot_localization}"},
      {"import rosbag", "--stamps TEXT:{header,receive}"},
  };
  for (const Listed& l : listed) {
    const auto r = run_cli(l.command + " --help");
    EXPECT_EQ(r.exit_code, 0) << l.command;
    EXPECT_NE(r.out.find(l.option), std::string::npos) << l.command << " --help:\n" << r.out;
  }
}

// tune --help shows which run each flag applies to: its help groups.
TEST(CliChoices, TuneHelpGroupsTheFlagsByTheRunTheyApplyTo) {
  const auto r = run_cli("tune --help");
  ASSERT_EQ(r.exit_code, 0);
  const auto at = [&r](const std::string& text) { return r.out.find(text); };
  for (const std::string heading :
       {"EKF, calibrator and UKF tunes (--track):", "robot_localization (--rl-params):",
        "robot_localization on a bag (--rl-params --bag):",
        "robot_localization on tracks (--rl-params --track):"})
    EXPECT_NE(at(heading), std::string::npos) << heading << "\n" << r.out;
  EXPECT_GT(at("  --resampler"), at("EKF, calibrator and UKF tunes (--track):"));
  EXPECT_LT(at("  --resampler"), at("robot_localization (--rl-params):"));
  EXPECT_GT(at("  --until"), at("robot_localization on a bag (--rl-params --bag):"));
  EXPECT_GT(at("  --odometry"), at("robot_localization on tracks (--rl-params --track):"));
}

// A flag that does not apply to what the command runs is refused by name in
// one line, before anything is read.
TEST(CliChoices, AFlagOfAnotherRunIsRefusedByName) {
  const std::string track = reference_track(1);
  const std::string rl_bag = "--rl-params " + kChoicesParams + " --bag " + kChoicesBag;
  const std::string rl_track = "--rl-params " + kChoicesParams + " --track " + track;
  const std::vector<WrongChoice> cases = {
      {"tune " + rl_bag + " --resampler systematic",
       "tune: --resampler does not apply to --rl-params (robot_localization's EKF)"},
      {"tune " + rl_bag + " --mode 3", "tune: --mode does not apply to --rl-params (robot_localization's EKF)"},
      {"tune " + rl_track + " --gps-topic /fix",
       "tune: --gps-topic does not apply to --rl-params with --track"},
      {"tune " + rl_track + " --end 20", "tune: --end does not apply to --rl-params with --track"},
      {"tune " + rl_bag + " --fix-sigma-m 0.1", "tune: --fix-sigma-m does not apply to --rl-params with --bag"},
      {"tune " + rl_bag + " --track " + track, "tune: --track does not apply to --rl-params with --bag"},
      {"tune --track " + track + " --fitness both", "tune: --fitness applies to --rl-params only"},
      {"tune --track " + track + " --until 10", "tune: --until applies to --rl-params only"},
      {"tune --track " + track + " --odometry wheels", "tune: --odometry applies to --rl-params only"},
      {"eval --track " + track + " --noise-from " + kChoicesParams,
       "eval: --noise-from applies to --rl-params only"},
      {"eval --track " + track + " --gyro-variance 0.1",
       "eval: --gyro-variance applies to --rl-params with --track only"},
      {"eval " + rl_track + " --fixes-out f.txt",
       "eval: --fixes-out applies to --rl-params with --bag, not with --track"},
  };
  for (const WrongChoice& c : cases) {
    const auto r = run_cli(c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_EQ(choice_error_lines(r.err), 1u) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << ": " << r.err;
  }
}

}  // namespace
}  // namespace odotune::cli

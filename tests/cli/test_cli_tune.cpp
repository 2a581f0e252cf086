// End-to-end: tune / eval / demo through the real binary.
#include <fstream>
#include <set>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fmt/format.h>

#include "support/cli_runner.h"

namespace odotune::cli {
namespace {

using testing_support::reference_track;
using testing_support::run_cli;
using testing_support::TempDir;

TEST(CliTune, JsonHasTheDocumentedKeysAndTunedBeatsBaseline) {
  TempDir tmp;
  const auto json_path = tmp / "out.json";
  const auto cfg_path = tmp / "cfg.yaml";
  const auto r = run_cli("tune --track " + reference_track(1) +
                         " --model alpha --mode 1 --seed 3 --particles 12 --iterations 15 --json " +
                         json_path.string() + " --config-out " + cfg_path.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("RMSE"), std::string::npos);
  const auto j = nlohmann::json::parse(testing_support::slurp(json_path));
  for (const char* key : {"model", "mode", "params", "baseline", "tuned", "evaluations", "seconds"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["model"], "alpha");
  EXPECT_EQ(j["mode"], 1);
  EXPECT_TRUE(j["params"].contains("alpha1"));
  EXPECT_TRUE(j["params"].contains("alpha2"));
  for (const char* m : {"rmse_m", "mae_m", "maxe_m"}) {
    EXPECT_TRUE(j["baseline"].contains(m));
    EXPECT_TRUE(j["tuned"].contains(m));
  }
  EXPECT_EQ(j["evaluations"], 12 * 16);
  EXPECT_LT(j["tuned"]["rmse_m"].get<double>(), j["baseline"]["rmse_m"].get<double>());

  // The written configuration replays to the same tuned RMSE.
  const auto jp = tmp / "eval.json";
  const auto e = run_cli("eval --config " + cfg_path.string() + " --track " + reference_track(1) + " --json " +
                         jp.string());
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const auto ej = nlohmann::json::parse(testing_support::slurp(jp));
  EXPECT_NEAR(ej["tracks"][0]["metrics"]["rmse_m"].get<double>(), j["tuned"]["rmse_m"].get<double>(), 1e-9);
}

TEST(CliTune, SameSeedSameResultAnyThreadCount) {
  TempDir tmp;
  std::string outs[2];
  const int threads[2] = {1, 2};
  for (int k = 0; k < 2; ++k) {
    const auto p = tmp / ("r" + std::to_string(k) + ".json");
    const auto r = run_cli("tune --track " + reference_track(2) +
                           " --model gyro --mode 4 --seed 9 --particles 10 --iterations 8 --threads " +
                           std::to_string(threads[k]) + " --json " + p.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto j = nlohmann::json::parse(testing_support::slurp(p));
    j.erase("seconds");
    outs[k] = j.dump();
  }
  EXPECT_EQ(outs[0], outs[1]);
}

TEST(CliTune, NloptSolverRuns) {
  TempDir tmp;
  const auto p = tmp / "n.json";
  const auto r = run_cli("tune --track " + reference_track(3) +
                         " --model rq --mode 2 --solver nlopt:SBPLX --evals 150 --seed 2 --json " + p.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(testing_support::slurp(p));
  EXPECT_LE(j["evaluations"].get<long>(), 151);
  EXPECT_EQ(j["params"].size(), 5u);
}

TEST(CliTune, BadTrackGivesOneLineWithFileLineAndReasonAndNoOutput) {
  TempDir tmp;
  const auto bad = tmp / "bad.csv";
  std::ofstream(bad) << "# format: odotune-track/1\n# robot.ticks_per_rev: 100\n"
                        "# robot.wheel_radius_left: 0.05\n# robot.wheel_radius_right: 0.05\n"
                        "# robot.wheel_base: 0.3\nt,ticks_l,ticks_r,gt_x,gt_y\n0,0,0,0,0\n"
                        "0.01,1,oops,0,0\n";
  const auto json_path = tmp / "out.json";
  const auto r = run_cli("tune --track " + bad.string() + " --json " + json_path.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(bad.string() + ":8:"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(json_path));
}

TEST(CliTune, RejectsBadOptionsClearly) {
  auto r = run_cli("tune --track " + reference_track(1) + " --mode 10");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("mode"), std::string::npos);
  // The UKF takes the ground-truth modes only.
  r = run_cli("tune --track " + reference_track(1) + " --model ukf --mode 9 --particles 4 --iterations 1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("mode"), std::string::npos) << r.err;
  r = run_cli("tune --track " + reference_track(1) + " --solver nlopt:NOPE");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("NOPE"), std::string::npos);
  r = run_cli("tune --track /nonexistent/x.csv");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("/nonexistent/x.csv"), std::string::npos);
}

TEST(CliEval, BadConfigNamesFileAndLine) {
  TempDir tmp;
  const auto cfg = tmp / "c.yaml";
  std::ofstream(cfg) << "format: odotune-ekf-config/1\nmodel: alpha\nparams:\n  alpha1: 0.1\n"
                        "  alpha3: 0.2\n";
  const auto r = run_cli("eval --config " + cfg.string() + " --track " + reference_track(1));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(cfg.string() + ":5:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("alpha3"), std::string::npos) << r.err;
}

TEST(CliDemo, PrintsTheTableForAllTracksAndModels) {
  const auto r = run_cli("demo --particles 6 --iterations 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::set<std::string> rows;
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string track, model;
    words >> track >> model;
    if (track.rfind("track", 0) == 0 && line.find("RMSE") == std::string::npos)
      rows.insert(track + " " + model);
  }
  for (int i = 1; i <= 5; ++i)
    for (const char* m : {"rq", "alpha", "gyro"})
      EXPECT_TRUE(rows.count("track" + std::to_string(i) + " " + m)) << i << " " << m << "\n" << r.out;
  EXPECT_EQ(rows.size(), 15u);
  EXPECT_NE(r.out.find("15 tunes"), std::string::npos) << r.out;
}

TEST(CliHelp, EveryCommandHasHelpWithAnExample) {
  for (const char* c : {"tune", "eval", "demo", "simulate", "import"}) {
    const auto r = run_cli(std::string(c) + " --help");
    EXPECT_EQ(r.exit_code, 0) << c;
    EXPECT_NE(r.out.find("Example"), std::string::npos) << c;
  }
}

// A recording without ground truth (the Husky of robot_localization's tests,
// imported from its MCAP form) is tuned by fix cross-validation, mode 8 by
// default, and says so; a ground-truth mode is refused in one line.
TEST(CliTune, WithoutGroundTruthTunesByFixCrossValidation) {
  const std::string dir = ::testing::TempDir();
  const std::string track = dir + "/odotune_cli_husky.csv";
  const std::string bag = std::string(ODOTUNE_SHARED_DIR) +
                          "/data/real/robot_localization_bags/ros2/test1.mcap";
  auto r = run_cli("import rosbag " + bag + " --imu-rpy 1.5707963267948966,0,-1.5707963267948966 -o " + track);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string json_file = dir + "/odotune_cli_husky.json";
  r = run_cli("tune --track " + track + " --model alpha --particles 8 --iterations 5 --json " + json_file);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("no ground truth in"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("mode 8 (held-out fix RMSE)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("NLL"), std::string::npos) << r.out;
  // eval scores it by its held-out fixes too, and writes its TUM trajectory on the bag's clock.
  const std::string tum = dir + "/odotune_cli_husky.tum";
  r = run_cli("eval --track " + track + " --trajectory-out " + tum);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("held-out fixes (no ground truth)"), std::string::npos) << r.out;
  {
    std::ifstream in(tum);
    std::string line;
    int poses = 0;
    double t_first = 0;
    while (std::getline(in, line))
      if (!line.empty() && line[0] != '#') {
        if (poses++ == 0) t_first = std::stod(line.substr(0, line.find(' ')));
      }
    EXPECT_GT(poses, 4000);
    EXPECT_NEAR(t_first, 1432235498.04, 0.05);  // the recording's clock (source.t0_ns)
  }
  std::remove(tum.c_str());
  // A grid with mode 8 stores it, and its run exports to robot_localization.
  const std::string exp = dir + "/odotune_cli_husky_exp.yaml", store = dir + "/odotune_cli_husky.sqlite";
  const std::string ekf = dir + "/odotune_cli_husky_ekf.yaml";
  std::remove(store.c_str());
  std::ofstream(exp) << "format: odotune-experiment/1\nname: husky\nmodels: [alpha]\ntracks: [" << track
                     << "]\nmodes: [8]\nseeds: [1]\nsolver: pso\nbudget: {particles: 6, iterations: 3}\n"
                        "leave_one_out: false\nstore: "
                     << store << "\n";
  r = run_cli("grid " + exp);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("export " + store + " --select mode=8 --format robot_localization --out " + ekf);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  {
    std::ifstream in(ekf);
    std::stringstream ss;
    ss << in.rdbuf();
    EXPECT_NE(ss.str().find("process_noise_covariance"), std::string::npos);
  }
  for (const std::string& f : {exp, store, ekf}) std::remove(f.c_str());
  r = run_cli("tune --track " + track + " --model alpha --mode 1 --particles 8 --iterations 5");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("use --mode 8 or 9"), std::string::npos) << r.err;
  std::remove(track.c_str());
  std::remove(json_file.c_str());
}

}  // namespace
}  // namespace odotune::cli

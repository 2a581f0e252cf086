// grid, report and export with model rl-ekf (robot_localization's EKF on the
// Husky bag and the user's parameter file), end to end through the binary:
// the grid's runs, the report's table and figures, and the exported file,
// which replays to the held-out figure the run stored.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <string>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

using odotune::testing_support::number_after;
using odotune::testing_support::run_cli;
using odotune::testing_support::slurp;
using odotune::testing_support::TempDir;

namespace {

const std::string kRlBags = std::string(ODOTUNE_SHARED_DIR) + "/data/real/robot_localization_bags";
const std::string kTf = "imu_link=0,-0.3,0.52,1.5707963267948966,0,-1.5707963267948966";

// An rl-ekf experiment on the ROS 2 form of test1, with `from` replaced by `to`.
std::filesystem::path experiment(const TempDir& dir, const std::string& name, const std::string& from = "",
                                 const std::string& to = "") {
  std::string text = "format: odotune-experiment/1\nname: " + name + "\nmodels: [rl-ekf]\ntracks: [" + kRlBags +
                     "/ros2/test1.mcap]\nrobot_localization:\n  params: " + kRlBags +
                     "/husky_ekf.yaml\n  tf: [\"" + kTf +
                     "\"]\n  gps_heading_fit_s: 60\n  until_s: 100\n  end_s: 160\n  fitness: [outage, both]\n"
                     "  space: blocks\n  input_covariances: false\n  outage_s: 30\nseeds: [1]\nsolver: pso\n"
                     "budget: {particles: 4, iterations: 2}\nstore: " +
                     name + ".sqlite\n";
  if (!from.empty()) text.replace(text.find(from), from.size(), to);
  const auto path = dir.path() / (name + ".yaml");
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(CliRlGrid, GridReportAndExportTakeTheRobotLocalizationModel) {
  TempDir dir("cli-rl-grid");
  const auto exp = experiment(dir, "rl");
  const auto store = dir.path() / "rl.sqlite";
  const auto g = run_cli("grid " + exp.string());
  ASSERT_EQ(g.exit_code, 0) << g.err;
  EXPECT_NE(g.out.find("2 runs in the experiment, 0 already stored, 2 run now"), std::string::npos) << g.out;
  const auto again = run_cli("grid " + exp.string());
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("2 already stored, 0 run now"), std::string::npos) << again.out;

  const auto report_dir = dir.path() / "report";
  const auto rep = run_cli("report " + store.string() + " --out " + report_dir.string());
  ASSERT_EQ(rep.exit_code, 0) << rep.err;
  EXPECT_NE(rep.out.find("held-out GPS-outage RMSE improvement per fitness: outage"), std::string::npos)
      << rep.out;
  const std::string table = slurp(report_dir / "table_rl.md");
  EXPECT_NE(table.find("| test1 | 10 |"), std::string::npos) << table;
  EXPECT_NE(table.find("| test1 | 11 |"), std::string::npos) << table;
  EXPECT_TRUE(std::filesystem::exists(report_dir / "trajectories_test1.png"));
  EXPECT_TRUE(std::filesystem::exists(report_dir / "convergence_test1.png"));
  EXPECT_NE(slurp(report_dir / "index.html").find("rl-ekf"), std::string::npos);

  // Two fitnesses: export asks for one; then the file replays to the run's figure.
  const auto out = dir.path() / "ekf.yaml";
  const auto mixed = run_cli("export " + store.string() +
                             " --select model=rl-ekf --format robot_localization "
                             "--out " +
                             out.string());
  EXPECT_NE(mixed.exit_code, 0);
  EXPECT_NE(mixed.err.find("--select mode="), std::string::npos) << mixed.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  const auto own = run_cli("export " + store.string() + " --select mode=10 --format odotune --out " +
                           out.string());
  EXPECT_NE(own.exit_code, 0);
  EXPECT_NE(own.err.find("--format robot_localization"), std::string::npos) << own.err;
  const auto x = run_cli("export " + store.string() + " --select mode=10 --format robot_localization --out " +
                         out.string());
  ASSERT_EQ(x.exit_code, 0) << x.err;
  const std::string text = slurp(out);
  EXPECT_NE(text.find("# odotune export from"), std::string::npos) << text;
  EXPECT_NE(text.find("yaw_offset"), std::string::npos) << text;  // navsat's fitted rotation
  const double stored = number_after(x.out, "held-out GPS-outage RMSE");
  ASSERT_GT(stored, 0.0) << x.out;
  const auto e = run_cli("eval --rl-params " + out.string() + " --bag " + kRlBags + "/ros2/test1.mcap --tf " +
                         kTf + " --gps-heading-fit 60 --from 100 --until 160");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NEAR(number_after(e.out, "GPS outage RMSE"), stored, 0.0015) << e.out << x.out;
  const auto ros1 = run_cli("export " + store.string() +
                            " --select mode=11 --format robot_localization --ros1 " + "--out " +
                            (dir.path() / "ekf1.yaml").string());
  ASSERT_EQ(ros1.exit_code, 0) << ros1.err;
  EXPECT_EQ(slurp(dir.path() / "ekf1.yaml").find("ros__parameters"), std::string::npos);
}

TEST(CliRlGrid, ExperimentMistakesAreOneLineNamingTheFile) {
  TempDir dir("cli-rl-grid-bad");
  const std::pair<std::filesystem::path, std::string> cases[] = {
      {experiment(dir, "mixed", "[rl-ekf]", "[rl-ekf, rq]"), "list it alone"},
      {experiment(dir, "modes", "seeds:", "modes: [7]\nseeds:"), "modes do not apply to rl-ekf"},
      {experiment(dir, "loo", "seeds:", "leave_one_out: true\nseeds:"),
       "leave_one_out is not supported for rl-ekf"},
      {experiment(dir, "key", "  outage_s: 30", "  smooth_lagged_data: true"),
       "unknown robot_localization key 'smooth_lagged_data'"},
      {experiment(dir, "fit", "[outage, both]", "[gt]"), "unknown fitness"},
      {experiment(dir, "late", "until_s: 100", "until_s: 170"), "end_s must be later"},
      {experiment(dir, "after", "until_s: 100\n  end_s: 160", "until_s: 500"), "leaves nothing to score"},
      {experiment(dir, "nomodel", "[rl-ekf]", "[rq]"), "needs model rl-ekf"},
  };
  for (const auto& [path, expected] : cases) {
    const auto r = run_cli("grid " + path.string());
    EXPECT_NE(r.exit_code, 0) << path;
    EXPECT_NE(r.err.find(expected), std::string::npos) << path << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / (path.stem().string() + ".sqlite"))) << path;
  }
  const auto t = run_cli("tune --model rl-ekf --track " + odotune::testing_support::reference_track(1));
  EXPECT_NE(t.exit_code, 0);
  EXPECT_NE(t.err.find("--rl-params"), std::string::npos) << t.err;
}

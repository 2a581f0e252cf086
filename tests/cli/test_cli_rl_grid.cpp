// grid, report and export with model rl-ekf (robot_localization's EKF on the
// Husky bag and the user's parameter file), end to end through the binary:
// the grid's runs, the report's table and figures, and the exported file,
// which replays to the held-out figure the run stored.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <regex>
#include <string>

#include <odotune/results/store.h>

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
                     "  space: blocks\n  input_covariances: false\n  outage_s: 30\n  grid_levels: [-1, 1]\n"
                     "  refine_decades: 0.5\n  profile_step_decades: 2\nseeds: [1]\nsolver: pso\n"
                     "budget: {particles: 4, iterations: 2}\nstore: " +
                     name + ".sqlite\n";
  if (!from.empty()) text.replace(text.find(from), from.size(), to);
  const auto path = dir.path() / (name + ".yaml");
  std::ofstream(path) << text;
  return path;
}

// How many filled circles of colour "rgb(r, g, b)" a gnuplot SVG draws.
std::size_t rl_svg_points(const std::string& svg, int r, int g, int b) {
  char colour[64];
  std::snprintf(colour, sizeof colour, "color='rgb(%3d, %3d, %3d)'", r, g, b);
  std::size_t n = 0;
  for (auto p = svg.find("<use xlink:href='#gpPt6' transform="); p != std::string::npos;
       p = svg.find("<use xlink:href='#gpPt6' transform=", p + 1))
    if (svg.compare(svg.find("color=", p), std::strlen(colour), colour) == 0) ++n;
  return n;
}

// The two numbers of a table_rl.md row "| test1 | MODE | original | tuned |"
// and which of them is in bold.
struct RlTableRow {
  double original_mm = 0, tuned_mm = 0;
  bool original_bold = false, tuned_bold = false;
};
RlTableRow rl_table_row(const std::string& md, int mode) {
  const std::regex re("\\| test1 \\| " + std::to_string(mode) +
                      R"( \| (\*\*)?([0-9.]+)(\*\*)? \| (\*\*)?([0-9.]+)(\*\*)? \|)");
  std::smatch m;
  if (!std::regex_search(md, m, re)) {
    ADD_FAILURE() << "no row for mode " << mode << " in\n" << md;
    return {};
  }
  return {std::stod(m[2]), std::stod(m[5]), m[1].matched, m[4].matched};
}

// A run of test1 as the grid would store it (space: blocks), with the given
// held-out RMSE and, when `ranges`, every parameter's range.
odotune::results::RunRecord rl_report_run(int mode, std::uint64_t seed, double baseline_m, double tuned_m,
                                          bool ranges) {
  odotune::results::RunRecord r;
  r.model = "rl-ekf";
  r.track = "test1";
  r.mode = mode;
  r.seed = seed;
  r.param_names = {"q_position", "q_orientation", "q_linear_velocity", "q_angular_velocity", "q_acceleration"};
  r.params = {2.0 + static_cast<double>(seed), 1.0, 0.5, 1.0, 0.25};
  if (ranges)
    r.param_ranges = {
        {1.5, 6.0, true}, {0.01, 100.0, false}, {0.3, 0.9, true}, {0.2, 5.0, false}, {0.1, 0.4, true}};
  r.best_fitness = tuned_m;
  r.baseline = {baseline_m, 0.8 * baseline_m, 2.0 * baseline_m};
  r.tuned = {tuned_m, 0.8 * tuned_m, 2.0 * tuned_m};
  r.evaluations = 8;
  r.convergence = {{4, 2.0 * tuned_m}, {8, tuned_m}};
  return r;
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
  const std::string html = slurp(report_dir / "index.html");
  EXPECT_NE(html.find("rl-ekf"), std::string::npos);
  // Every run is in the improvement figure: one point per run and metric
  // (RMSE blue, MAE orange, MAXE green), though each box holds one run.
  const std::string box = slurp(report_dir / "boxplots.svg");
  EXPECT_EQ(rl_svg_points(box, 0, 114, 178), 2u) << "RMSE";
  EXPECT_EQ(rl_svg_points(box, 230, 159, 0), 2u) << "MAE";
  EXPECT_EQ(rl_svg_points(box, 0, 158, 115), 2u) << "MAXE";
  // The lower (better) RMSE of each row is the bold one.
  for (int mode : {10, 11}) {
    const RlTableRow row = rl_table_row(table, mode);
    EXPECT_EQ(row.original_bold, row.original_mm <= row.tuned_mm) << table;
    EXPECT_EQ(row.tuned_bold, row.tuned_mm <= row.original_mm) << table;
  }
  // One seed: the spread section says so in one line. Each run profiled its
  // parameters: their ranges are stored and drawn.
  EXPECT_NE(html.find("One seed per bag and fitness: no spread over seeds to show"), std::string::npos);
  EXPECT_NE(html.find("What the recording determined"), std::string::npos);
  EXPECT_EQ(html.find("No parameter ranges are stored for these runs"), std::string::npos);
  for (int mode : {10, 11})
    EXPECT_TRUE(std::filesystem::exists(report_dir / ("ranges_test1_" + std::to_string(mode) + ".svg")))
        << mode;
  for (const auto& run : odotune::results::Store(store).runs()) {
    EXPECT_EQ(run.param_ranges.size(), run.param_names.size());
    for (std::size_t i = 0; i < run.params.size(); ++i) {
      if (!run.param_ranges[i].determined) {
        EXPECT_EQ(run.params[i], 1.0) << run.param_names[i];
      }
    }
  }

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

// Three seeds with parameter ranges, written into a store directly (the tune
// does not fill ranges yet): the seeds' spread as min / median / max, one
// point per seed in the improvement figure, and each parameter's range.
TEST(CliRlGrid, ReportShowsTheSeedsSpreadAndWhatTheRecordingDetermined) {
  TempDir dir("cli-rl-report-seeds");
  const auto exp = experiment(dir, "rl3", "seeds: [1]", "seeds: [1, 2, 3]");
  const auto store = dir.path() / "rl3.sqlite";
  {
    const std::string text = slurp(exp);
    odotune::results::Store s(store,
                              {"rl3", text, odotune::results::experiment_hash(text), "test", exp.string()});
    // Outage: improvements -50, +10, +20 %; both: -100, -20, +40 % (baseline 2 m).
    const double outage[] = {3.0, 1.8, 1.6}, both[] = {4.0, 2.4, 1.2};
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      s.add(rl_report_run(10, seed, 2.0, outage[seed - 1], true));
      s.add(rl_report_run(11, seed, 2.0, both[seed - 1], seed != 2));  // seed 2 stored without ranges
    }
  }
  const auto out = dir.path() / "report";
  const auto rep = run_cli("report " + store.string() + " --out " + out.string());
  ASSERT_EQ(rep.exit_code, 0) << rep.err;
  const std::string html = slurp(out / "index.html");

  // The spread over seeds.
  const std::string seeds = slurp(out / "table_rl_seeds.md");
  EXPECT_NE(seeds.find("| test1 | outage | 3 | -50.0 % | +10.0 % | +20.0 % | 1600.00 | 1800.00 | 3000.00 |"),
            std::string::npos)
      << seeds;
  EXPECT_NE(seeds.find("| test1 | both | 3 | -100.0 % | -20.0 % | +40.0 % | 1200.00 | 2400.00 | 4000.00 |"),
            std::string::npos)
      << seeds;
  EXPECT_NE(html.find("Spread over seeds"), std::string::npos);
  EXPECT_NE(html.find("<td class=\"num\">+10.0 %</td>"), std::string::npos);
  // One point per seed, fitness and metric in the improvement figure.
  const std::string box = slurp(out / "boxplots.svg");
  EXPECT_EQ(rl_svg_points(box, 0, 114, 178), 6u) << "RMSE";
  EXPECT_EQ(rl_svg_points(box, 230, 159, 0), 6u) << "MAE";
  EXPECT_EQ(rl_svg_points(box, 0, 158, 115), 6u) << "MAXE";
  // Means in the table; the original (2000 mm) is better than both means, so bold.
  const std::string table = slurp(out / "table_rl.md");
  EXPECT_NE(table.find("| test1 | 10 | **2000.00** | 2133.33 |"), std::string::npos) << table;
  EXPECT_NE(table.find("| test1 | 11 | **2000.00** | 2533.33 |"), std::string::npos) << table;

  // What the recording determined: per bag × fitness × parameter, each seed's factor and range.
  const std::string ranges = slurp(out / "table_rl_ranges.md");
  EXPECT_NE(ranges.find("| Track | Fitness | Parameter | seed 1 | seed 2 | seed 3 |"), std::string::npos)
      << ranges;
  EXPECT_NE(ranges.find("| test1 | outage | q_position | 3 [1.5, 6] | 4 [1.5, 6] | 5 [1.5, 6] |"),
            std::string::npos)
      << ranges;
  EXPECT_NE(ranges.find("| test1 | outage | q_orientation | 1, not determined by this recording [0.01, 100] |"),
            std::string::npos)
      << ranges;
  EXPECT_NE(
      ranges.find("| test1 | both | q_acceleration | 0.25 [0.1, 0.4] | 0.25, no range stored | 0.25 [0.1, "
                  "0.4] |"),
      std::string::npos)
      << ranges;
  EXPECT_NE(html.find("What the recording determined"), std::string::npos);
  EXPECT_NE(html.find("not determined by this recording [0.2, 5]"), std::string::npos);
  EXPECT_EQ(html.find("No parameter ranges are stored"), std::string::npos);
  for (const std::string mode : {"10", "11"}) {
    const std::string svg = slurp(out / ("ranges_test1_" + mode + ".svg"));
    for (const std::string label : {"q_position", "q_acceleration", "seed 1", "seed 3", "not determined",
                                    "the file's value (factor 1)", "tuned value"})
      EXPECT_NE(svg.find(label), std::string::npos) << mode << " lacks " << label;
    // A dot per parameter and seed with ranges (3 seeds for outage, 2 for both), and the legend's.
    EXPECT_EQ(rl_svg_points(svg, 0, 0, 0), (mode == "10" ? 15u : 10u) + 1u) << mode;
  }
  EXPECT_EQ(html.find("<script"), std::string::npos);
}

// Model rl-ukf: the same experiment run by ukf_node (the Husky's file read as
// the UKF's; one grid level and a short span keep it to seconds, the UKF being
// ~35× slower); the report names it, and the exported file says it is the
// UKF's (alpha, kappa, beta written) and replays to the run's stored figure.
TEST(CliRlGrid, UkfModelGoesThroughGridReportAndExport) {
  TempDir dir("cli-rl-ukf-grid");
  const auto exp = experiment(dir, "rlukf", "models: [rl-ekf]", "models: [rl-ukf]");
  std::string text = slurp(exp);
  for (const auto& [from, to] :
       std::vector<std::pair<std::string, std::string>>{{"until_s: 100", "until_s: 60"},
                                                        {"end_s: 160", "end_s: 90"},
                                                        {"fitness: [outage, both]", "fitness: [heldout-fixes]"},
                                                        {"grid_levels: [-1, 1]", "grid_levels: [0]"}})
    text.replace(text.find(from), from.size(), to);
  std::ofstream(exp) << text;
  const auto store = dir.path() / "rlukf.sqlite";
  const auto g = run_cli("grid " + exp.string());
  ASSERT_EQ(g.exit_code, 0) << g.err;
  const auto runs = odotune::results::Store(store).runs();
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].model, "rl-ukf");
  const auto report_dir = dir.path() / "report";
  const auto rep = run_cli("report " + store.string() + " --out " + report_dir.string());
  ASSERT_EQ(rep.exit_code, 0) << rep.err;
  const std::string html = slurp(report_dir / "index.html");
  EXPECT_NE(html.find("robot_localization's UKF (model rl-ukf)"), std::string::npos);
  const auto out = dir.path() / "ukf.yaml";
  const auto x = run_cli("export " + store.string() + " --format robot_localization --out " + out.string());
  ASSERT_EQ(x.exit_code, 0) << x.err;
  const std::string file = slurp(out);
  EXPECT_NE(file.find("alpha:"), std::string::npos) << file;
  const double stored = number_after(x.out, "held-out GPS-outage RMSE");
  ASSERT_GT(stored, 0.0) << x.out;
  const auto e = run_cli("eval --rl-params " + out.string() + " --bag " + kRlBags + "/ros2/test1.mcap --tf " +
                         kTf + " --gps-heading-fit 60 --from 60 --until 90");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NE(e.out.find("robot_localization UKF"), std::string::npos) << e.out;
  EXPECT_NEAR(number_after(e.out, "GPS outage RMSE"), stored, 0.0015) << e.out << x.out;
}

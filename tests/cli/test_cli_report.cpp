// odotune report end to end: a small leave-one-track-out grid, then the
// report's files checked against the store's own numbers.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include <fmt/format.h>

#include <odotune/results/store.h>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;
using testing_support::reference_track;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::TempDir;

// 2 models × 2 tracks × 2 modes × 2 seeds, plus the leave-one-out cells.
std::string experiment(const std::string& track_a, const std::string& track_b) {
  return fmt::format("format: odotune-experiment/1\nname: report-test\nmodels: [rq, gyro]\n"
                     "tracks: [{}, {}]\nmodes: [1, 7]\nseeds: [1, 2]\nsolver: pso\n"
                     "budget: {{particles: 8, iterations: 6}}\nleave_one_out: true\nstore: s.sqlite\n",
                     track_a, track_b);
}

void expect_png(const fs::path& p) {
  const std::string bytes = slurp(p);
  EXPECT_GT(bytes.size(), 1024u) << p;
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << p;
}

void expect_labels(const fs::path& svg, const std::vector<std::string>& labels) {
  const std::string s = slurp(svg);
  ASSERT_NE(s.find("</svg>"), std::string::npos) << svg;
  for (const auto& l : labels) EXPECT_NE(s.find(l), std::string::npos) << svg << " lacks " << l;
}

class CliReport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("report");
    std::ofstream(*dir_ / "e.yaml") << experiment(reference_track(1), reference_track(5));
    const auto g = run_cli("grid " + (*dir_ / "e.yaml").string());
    ASSERT_EQ(g.exit_code, 0) << g.err;
    report_ = new testing_support::CliResult(
        run_cli("report " + (*dir_ / "s.sqlite").string() + " --out " + (*dir_ / "r").string()));
  }
  static void TearDownTestSuite() {
    delete report_;
    delete dir_;
  }
  static TempDir* dir_;
  static testing_support::CliResult* report_;
};
TempDir* CliReport::dir_ = nullptr;
testing_support::CliResult* CliReport::report_ = nullptr;

TEST_F(CliReport, WritesEveryFigureAsPngAndSvgWithItsLabels) {
  ASSERT_EQ(report_->exit_code, 0) << report_->err;
  const fs::path r = *dir_ / "r";
  for (const std::string model : {"rq", "gyro"})
    for (const std::string metric : {"rmse", "mae", "maxe"})
      for (const std::string kind : {"", "heldout_"}) {
        const fs::path stem = r / ("heatmap_" + kind + model + "_" + metric);
        expect_png(stem.string() + ".png");
        std::string upper = metric;
        for (auto& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        expect_labels(stem.string() + ".svg", {"fitness mode", "track1", "track5", "7 RMSE+MAE+MAXE",
                                               upper + " improvement [%], " + model, "improvement [%]"});
      }
  for (const std::string stem : {"boxplots", "boxplots_heldout"}) {
    expect_png(r / (stem + ".png"));
    expect_labels(r / (stem + ".svg"), {"rq", "gyro", "RMSE", "MAE", "MAXE", "improvement"});
  }
  for (const std::string track : {"track1", "track5"}) {
    expect_png(r / ("trajectories_" + track + ".png"));
    expect_labels(r / ("trajectories_" + track + ".svg"),
                  {"ground truth", "baseline EKF", "rq tuned", "gyro tuned", "x [m]", "y [m]"});
    expect_png(r / ("convergence_" + track + ".png"));
    expect_labels(r / ("convergence_" + track + ".svg"), {"evaluations", "rq", "gyro"});
  }
  EXPECT_NE(report_->out.find("mean RMSE improvement over the baseline: rq "), std::string::npos)
      << report_->out;
}

TEST_F(CliReport, NumbersAreTheStoresMeans) {
  ASSERT_EQ(report_->exit_code, 0) << report_->err;
  const results::Store store(*dir_ / "s.sqlite");
  // Per-track and held-out RMSE improvement of gyro on track5, mode 7, and
  // the table's original and tuned RMSE, recomputed from the rows.
  double own = 0, held = 0, base = 0, tuned = 0;
  int n_own = 0, n_held = 0;
  for (const auto& run : store.runs()) {
    if (run.model != "gyro" || run.mode != 7) continue;
    if (run.heldout_track == "track5") held += run.improvement_rmse_pct(), ++n_held;
    if (run.track == "track5") {
      own += run.improvement_rmse_pct(), ++n_own;
      base += run.baseline.rmse_m, tuned += run.tuned.rmse_m;
    }
  }
  ASSERT_EQ(n_own, 2);
  ASSERT_EQ(n_held, 2);
  const fs::path r = *dir_ / "r";
  expect_labels(r / "heatmap_gyro_rmse.svg", {fmt::format(">{:.1f}<", own / n_own)});
  expect_labels(r / "heatmap_heldout_gyro_rmse.svg", {fmt::format(">{:.1f}<", held / n_held)});
  const std::string csv = slurp(r / "table1.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "track,mode,original_mm,rq_mm,gyro_mm");
  const std::string row = fmt::format("\ntrack5,7,{:.2f},", base / n_own * 1e3);
  const auto at = csv.find(row);
  ASSERT_NE(at, std::string::npos) << csv;
  EXPECT_NE(csv.find(fmt::format(",{:.2f}\n", tuned / n_own * 1e3), at), std::string::npos) << csv;
  EXPECT_NE(slurp(r / "table1.md").find("| Track | Mode | Original [mm] | rq [mm] | gyro [mm] |"),
            std::string::npos);
  EXPECT_NE(slurp(r / "generalisation.md").find("held out"), std::string::npos);
}

TEST_F(CliReport, HtmlPageIsSelfContainedAndHoldsEveryFigure) {
  ASSERT_EQ(report_->exit_code, 0) << report_->err;
  const fs::path r = *dir_ / "r";
  const std::string html = slurp(r / "index.html");
  std::size_t svgs = 0;
  for (const auto& e : fs::directory_iterator(r)) svgs += e.path().extension() == ".svg";
  std::size_t inlined = 0;
  for (auto p = html.find("<svg"); p != std::string::npos; p = html.find("<svg", p + 1)) ++inlined;
  EXPECT_EQ(inlined, svgs);
  EXPECT_EQ(svgs,
            12u + 2u + 4u);  // 2 models × 3 metrics × 2 kinds of heatmap, boxplots, trajectories + convergence
  for (const std::string label : {"Figure 3", "Figure 4", "Table 1", "Figure 5", "Convergence", "held out",
                                  "ground truth", "fitness mode", "track5"})
    EXPECT_NE(html.find(label), std::string::npos) << label;
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("<?xml"), std::string::npos);
}

TEST_F(CliReport, MovedTracksLeaveOutTheOverlayUnlessGivenWithTrack) {
  ASSERT_EQ(report_->exit_code, 0) << report_->err;
  TempDir d("report-moved");
  fs::copy_file(reference_track(1), d / "track1.csv");
  fs::copy_file(reference_track(5), d / "track5.csv");
  std::ofstream(d / "e.yaml") << experiment("track1.csv", "track5.csv");
  ASSERT_EQ(run_cli("grid " + (d / "e.yaml").string()).exit_code, 0);
  fs::remove(d / "track1.csv");
  fs::remove(d / "track5.csv");
  const auto a = run_cli("report " + (d / "s.sqlite").string() + " --out " + (d / "a").string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_NE(a.out.find("trajectory overlay of track1 left out"), std::string::npos) << a.out;
  EXPECT_FALSE(fs::exists(d / "a" / "trajectories_track1.svg"));
  const auto b = run_cli("report " + (d / "s.sqlite").string() + " --out " + (d / "b").string() +
                         " --track-name track5 --track " + reference_track(5));
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_TRUE(fs::exists(d / "b" / "trajectories_track5.svg"));
  EXPECT_FALSE(fs::exists(d / "b" / "trajectories_track1.svg"));
}

TEST(CliReportErrors, OneLineAndNoOutput) {
  TempDir d("report-errors");
  const auto missing = run_cli("report " + (d / "none.sqlite").string() + " --out " + (d / "o").string());
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.err.find("none.sqlite: no such results store"), std::string::npos) << missing.err;
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
  EXPECT_FALSE(fs::exists(d / "o"));

  std::ofstream(d / "e.yaml") << experiment(reference_track(1), reference_track(5));
  ASSERT_EQ(run_cli("grid " + (d / "e.yaml").string()).exit_code, 0);
  const auto bad = run_cli("report " + (d / "s.sqlite").string() + " --out " + (d / "o").string() +
                           " --track-name nope");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("'nope' is not a track of this store, expected one of track1, track5"),
            std::string::npos)
      << bad.err;
  EXPECT_FALSE(fs::exists(d / "o"));
  const auto mode = run_cli("report " + (d / "s.sqlite").string() + " --out " + (d / "o").string() +
                            " --mode 10");
  EXPECT_NE(mode.exit_code, 0);
  EXPECT_NE(mode.err.find("--mode 10 is out of range"), std::string::npos) << mode.err;

  std::ofstream(d / "junk.sqlite") << "not a database at all, just text\n";
  const auto junk = run_cli("report " + (d / "junk.sqlite").string() + " --out " + (d / "o").string());
  EXPECT_NE(junk.exit_code, 0);
  EXPECT_NE(junk.err.find("junk.sqlite"), std::string::npos) << junk.err;
  EXPECT_FALSE(fs::exists(d / "o"));
}

}  // namespace
}  // namespace odotune::cli

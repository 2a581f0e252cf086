// odotune study resampling|calibration end to end on a short wheelchair drive
// (~20 s instead of 2 minutes, so that the whole file runs in seconds); the
// study's computation helpers are tested in tests/studies.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <odotune/formats/scenario_yaml.h>
#include <odotune/studies/calibration_study.h>
#include <odotune/studies/study_outputs.h>
#include <odotune/studies/study_tables.h>

#include "support/cli_runner.h"
#include "support/study_fixtures.h"
#include "support/temp_dir.h"

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::TempDir;
using namespace odotune::study_fixtures;

// ---------------------------------------------------------------- end to end

class CliStudy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("study");
    std::ofstream(*dir_ / "short.yaml") << short_scenario();
    std::ofstream(*dir_ / "short_step.yaml") << short_scenario(10.0);
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string resampling(const std::string& out, int seed) {
    return "study resampling --out " + (*dir_ / out).string() + " --runs 2 --particles 1000 --seed " +
           std::to_string(seed) + " --scenario " + (*dir_ / "short.yaml").string();
  }
  static std::string calibration(const std::string& out, int seed) {
    return "study calibration --out " + (*dir_ / out).string() + " --runs 2 --particles 2000 --seed " +
           std::to_string(seed) + " --scenario " + (*dir_ / "short.yaml").string() + " --step-scenario " +
           (*dir_ / "short_step.yaml").string();
  }
  static TempDir* dir_;
};
TempDir* CliStudy::dir_ = nullptr;

void expect_png_svg(const fs::path& stem) {
  const std::string png = slurp(stem.string() + ".png");
  EXPECT_GT(png.size(), 1024u) << stem;
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << stem;
  EXPECT_NE(slurp(stem.string() + ".svg").find("</svg>"), std::string::npos) << stem;
}

TEST_F(CliStudy, ResamplingWritesTable1WithTwelvePlausibleRowsAndIsReproducible) {
  const auto r = run_cli(resampling("rs_a", 3));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path out = *dir_ / "rs_a";
  for (const char* f : {"table1.md", "table1.csv", "table1_runs.csv"}) EXPECT_TRUE(fs::exists(out / f)) << f;
  expect_png_svg(out / "fig3_4_resampling");
  EXPECT_NE(r.out.find("| Systematic | neff |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(out.string()), std::string::npos) << r.out;  // says where the files went

  const Csv t = parse_csv(slurp(out / "table1.csv"));
  ASSERT_EQ(t.rows.size(), 12u);
  for (const char* c : {"resampler", "policy", "runs", "err_rr_m_mean", "err_rr_m_sd", "err_rl_m_mean",
                        "v_rmse_m_s_mean", "w_rmse_rad_s_mean", "resampled_fraction_mean", "ms_per_iter_mean"})
    t.col(c);
  std::map<std::string, int> per_resampler, per_policy;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    ++per_resampler[t.rows[i][t.col("resampler")]];
    ++per_policy[t.rows[i][t.col("policy")]];
    EXPECT_EQ(t.num(i, "runs"), 2);
    // Radius errors: inside the width of the PF's initial range (30 mm);
    // a 20 s drive with 1000 particles leaves a few mm.
    for (const char* c : {"err_rr_m_mean", "err_rl_m_mean"}) {
      EXPECT_TRUE(std::isfinite(t.num(i, c))) << c;
      EXPECT_GE(t.num(i, c), 0.0);
      EXPECT_LT(t.num(i, c), 0.03) << c << " row " << i;
    }
    // Velocity errors: of the order of the 0.02 m/s, 0.02 rad/s measurement noise at most.
    EXPECT_GT(t.num(i, "v_rmse_m_s_mean"), 0.0);
    EXPECT_LT(t.num(i, "v_rmse_m_s_mean"), 0.05);
    EXPECT_GT(t.num(i, "w_rmse_rad_s_mean"), 0.0);
    EXPECT_LT(t.num(i, "w_rmse_rad_s_mean"), 0.1);
    EXPECT_GT(t.num(i, "ms_per_iter_mean"), 0.0);
    const double f = t.num(i, "resampled_fraction_mean");
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
  }
  EXPECT_EQ(per_resampler.size(), 4u);
  for (const char* p : {"neff", "max", "every"}) EXPECT_EQ(per_policy[p], 4) << p;

  const std::string md = slurp(out / "table1.md");
  EXPECT_NE(md.find("0.002623"), std::string::npos);  // the paper's Table I beside ours
  EXPECT_NE(md.find("Fariña"), std::string::npos);
  EXPECT_NE(md.find("--runs 2"), std::string::npos);  // the command that regenerates it

  // Same seed: identical numbers except timing; another seed: different.
  ASSERT_EQ(run_cli(resampling("rs_b", 3)).exit_code, 0);
  ASSERT_EQ(run_cli(resampling("rs_c", 4)).exit_code, 0);
  const std::string a = without_timing(slurp(out / "table1_runs.csv"));
  EXPECT_EQ(a, without_timing(slurp(*dir_ / "rs_b" / "table1_runs.csv")));
  EXPECT_EQ(without_timing(slurp(out / "table1.csv")), without_timing(slurp(*dir_ / "rs_b" / "table1.csv")));
  EXPECT_NE(a, without_timing(slurp(*dir_ / "rs_c" / "table1_runs.csv")));
}

TEST_F(CliStudy, CalibrationWritesTable2AndFiguresWithCheckableNumbers) {
  const auto r = run_cli(calibration("cs_a", 5));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path out = *dir_ / "cs_a";
  for (const char* f : {"table2.md", "table2.csv", "table2_runs.csv"}) EXPECT_TRUE(fs::exists(out / f)) << f;
  for (const char* f : {"fig5_particles", "fig6a_radii_constant", "fig6b_radii_step", "fig8_dkf_vs_pf_step",
                        "fig8_dkf_vs_pf_constant"})
    expect_png_svg(out / f);

  const Csv t = parse_csv(slurp(out / "table2.csv"));
  ASSERT_EQ(t.rows.size(), 8u);
  const std::vector<std::string> methods = {"adaptive-pf", "dkf", "batch-velocity", "none"};
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(t.rows[i][t.col("track")], i < 4 ? "constant" : "step");
    EXPECT_EQ(t.rows[i][t.col("method")], methods[i % 4]);
    for (const char* c : {"err_rr_m_mean", "err_rl_m_mean", "pose_rmse_m_mean", "heading_rmse_rad_mean"}) {
      EXPECT_TRUE(std::isfinite(t.num(i, c))) << c << " row " << i;
      EXPECT_GE(t.num(i, c), 0.0);
    }
    const bool online = i % 4 < 2;
    EXPECT_EQ(t.rows[i][t.col("converged_runs")].empty(), !online) << i;
    EXPECT_EQ(t.rows[i][t.col("reconverged_runs")].empty(), !(online && i >= 4)) << i;
  }

  // "none" keeps the nominal radii: its final errors are the drawn truth's
  // offsets, 0.32·|1 − scale| (× the step's scale after the step).
  const Csv runs = parse_csv(slurp(out / "table2_runs.csv"));
  ASSERT_EQ(runs.rows.size(), 16u);
  int checked = 0;
  for (std::size_t i = 0; i < runs.rows.size(); ++i) {
    if (runs.rows[i][runs.col("method")] != "none") continue;
    const bool step = runs.rows[i][runs.col("track")] == "step";
    const double true_r = kNominalRadius * runs.num(i, "truth_scale_r") * (step ? 0.99 : 1.0);
    const double true_l = kNominalRadius * runs.num(i, "truth_scale_l") * (step ? 0.985 : 1.0);
    EXPECT_NEAR(runs.num(i, "err_rr_m"), std::abs(true_r - kNominalRadius), 1e-12);
    EXPECT_NEAR(runs.num(i, "err_rl_m"), std::abs(true_l - kNominalRadius), 1e-12);
    ++checked;
  }
  EXPECT_EQ(checked, 4);
  // Every calibrated method ends closer to the truth than the 2 % it could
  // start from, and dead-reckons a 20 s drive to within a metre.
  for (std::size_t i = 0; i < runs.rows.size(); ++i) {
    if (runs.rows[i][runs.col("method")] == "none") continue;
    EXPECT_LT(runs.num(i, "err_rr_m"), 0.02 * kNominalRadius) << i;
    EXPECT_LT(runs.num(i, "err_rl_m"), 0.02 * kNominalRadius) << i;
    EXPECT_LT(runs.num(i, "pose_rmse_m"), 1.0) << i;
  }
  const std::string md = slurp(out / "table2.md");
  EXPECT_NE(md.find("32.55"), std::string::npos);  // the paper's Table II beside ours
  EXPECT_NE(md.find("short_step"), std::string::npos);

  ASSERT_EQ(run_cli(calibration("cs_b", 5)).exit_code, 0);
  EXPECT_EQ(without_timing(slurp(out / "table2_runs.csv")),
            without_timing(slurp(*dir_ / "cs_b" / "table2_runs.csv")));
}

TEST_F(CliStudy, BadInputIsOneLineAndNonZeroExit) {
  // --out under a regular file.
  std::ofstream(*dir_ / "a_file") << "x";
  const auto bad_out = run_cli("study resampling --runs 1 --particles 100 --scenario " +
                               (*dir_ / "short.yaml").string() + " --out " +
                               (*dir_ / "a_file" / "sub").string());
  EXPECT_NE(bad_out.exit_code, 0);
  EXPECT_EQ(std::count(bad_out.err.begin(), bad_out.err.end(), '\n'), 1) << bad_out.err;
  EXPECT_NE(bad_out.err.find("a_file"), std::string::npos) << bad_out.err;
  EXPECT_FALSE(fs::exists(*dir_ / "a_file" / "sub"));

  const auto bad_runs = run_cli("study calibration --runs 0 --out " + (*dir_ / "never").string());
  EXPECT_NE(bad_runs.exit_code, 0);
  EXPECT_EQ(std::count(bad_runs.err.begin(), bad_runs.err.end(), '\n'), 1) << bad_runs.err;
  EXPECT_NE(bad_runs.err.find("runs = 0"), std::string::npos) << bad_runs.err;
  EXPECT_FALSE(fs::exists(*dir_ / "never"));

  const auto missing = run_cli("study resampling --out " + (*dir_ / "never").string() + " --scenario " +
                               (*dir_ / "no_such.yaml").string());
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
  EXPECT_FALSE(fs::exists(*dir_ / "never"));
}

}  // namespace
}  // namespace odotune::cli

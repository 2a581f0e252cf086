// odotune study resampling|calibration: the computation helpers
// (studies/calibration_study.h), the tables and figure data, and the command end
// to end on a short wheelchair drive (~20 s instead of 2 minutes, so that the
// whole file runs in seconds).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "studies/calibration_study.h"
#include "support/cli_runner.h"
#include "formats/scenario_yaml.h"
#include "studies/study_outputs.h"
#include "studies/study_tables.h"
#include "support/temp_dir.h"

namespace odotune {
namespace {

namespace fs = std::filesystem;
using odotune::MeanSd;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::TempDir;

constexpr double kNominalRadius = 0.32;

// The wheelchair of scenarios/wheelchair.yaml on a short drive with turns
// both ways; `step_at_s` > 0 adds a radius_step then.
std::string short_scenario(double step_at_s = 0.0) {
  std::string s =
      "name: short_chair\nseed: 1\n"
      "robot: {wheel_radius_left_m: 0.32, wheel_radius_right_m: 0.32, wheel_base_m: 0.65, ticks_per_rev: 8800}\n"
      "motion:\n  max_accel_m_s2: 0.4\n  max_angular_accel_rad_s2: 1.0\n  segments:\n"
      "    - stop: {duration_s: 1}\n"
      "    - straight: {distance_m: 4, speed_m_s: 0.8}\n"
      "    - arc: {radius_m: 1.0, angle_deg: 90, speed_m_s: 0.5}\n"
      "    - arc: {radius_m: 1.0, angle_deg: -120, speed_m_s: 0.5}\n"
      "    - straight: {distance_m: 3, speed_m_s: 0.8}\n"
      "    - spin: {angle_deg: 90, rate_deg_s: 45}\n"
      "    - stop: {duration_s: 1}\n"
      "sensors:\n  power: {enabled: false}\n  aps: {enabled: false}\n"
      "effects:\n  radius_error: {scale_l: 1.01, scale_r: 0.99}\n  wheel_base_error: {scale: 1.02}\n";
  if (step_at_s > 0.0)
    s += "  radius_step: {t: " + std::to_string(step_at_s) + ", scale_l: 0.985, scale_r: 0.99}\n";
  return s;
}

sim::Scenario parsed(double step_at_s = 0.0) {
  return odotune::parse_scenario(short_scenario(step_at_s), step_at_s > 0 ? "short_step.yaml" : "short.yaml");
}

// CSV text → header and rows of fields.
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::size_t col(const std::string& name) const {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
  double num(std::size_t row, const std::string& name) const {
    const std::string& f = rows.at(row).at(col(name));
    return f.empty() ? NAN : std::stod(f);
  }
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string f;
  while (std::getline(ss, f, ',')) out.push_back(f);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

Csv parse_csv(const std::string& text) {
  Csv c;
  std::stringstream ss(text);
  std::string line;
  std::getline(ss, line);
  c.header = split(line);
  while (std::getline(ss, line))
    if (!line.empty()) c.rows.push_back(split(line));
  return c;
}

// The CSV without its timing columns (ms_per_iter*).
std::string without_timing(const std::string& text) {
  const Csv c = parse_csv(text);
  std::string out;
  const auto keep = [&](std::size_t i) { return c.header[i].rfind("ms_per_iter", 0) != 0; };
  for (std::size_t i = 0; i < c.header.size(); ++i)
    if (keep(i)) out += c.header[i] + ",";
  out += "\n";
  for (const auto& r : c.rows) {
    for (std::size_t i = 0; i < r.size(); ++i)
      if (keep(i)) out += r[i] + ",";
    out += "\n";
  }
  return out;
}

// ---------------------------------------------------------------- helpers

TEST(StudyMeanSd, SampleStatisticsOverFiniteValues) {
  const MeanSd m = odotune::mean_sd({1.0, 2.0, 3.0, 4.0});
  EXPECT_EQ(m.n, 4);
  EXPECT_DOUBLE_EQ(m.mean, 2.5);
  EXPECT_NEAR(m.sd, std::sqrt(5.0 / 3.0), 1e-15);  // Σ(x − 2.5)² = 5, n − 1 = 3
  const MeanSd with_nan = odotune::mean_sd({NAN, 2.0, NAN, 4.0});
  EXPECT_EQ(with_nan.n, 2);
  EXPECT_DOUBLE_EQ(with_nan.mean, 3.0);
  EXPECT_NEAR(with_nan.sd, std::sqrt(2.0), 1e-15);
  const MeanSd one = odotune::mean_sd({7.0});
  EXPECT_EQ(one.n, 1);
  EXPECT_DOUBLE_EQ(one.sd, 0.0);
  const MeanSd none = odotune::mean_sd({NAN});
  EXPECT_EQ(none.n, 0);
  EXPECT_TRUE(std::isnan(none.mean) && std::isnan(none.sd));
  EXPECT_EQ(odotune::mean_sd_text(none), "–");
  EXPECT_EQ(odotune::mean_sd_text(m), "2.5 ± 1.3");
}

TEST(StudyOptions, IsValidNamesTheBadValue) {
  odotune::StudyOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.runs = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("runs = 0"), std::string::npos) << why;
  o = {};
  o.truth_radius_spread = 0.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("truth_radius_spread"), std::string::npos) << why;
  o = {};
  o.pf_particles = 3;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("pf_particles = 3"), std::string::npos) << why;
}

TEST(StudyDraws, SeedPerRunTruthWithinSpreadDkfWithinThePfRanges) {
  odotune::StudyOptions o;
  o.seed = 40;
  o.truth_radius_spread = 0.02;
  const sim::Scenario sc = parsed(10.0);
  std::map<double, int> seen;
  for (int r = 0; r < 20; ++r) {
    const odotune::McDraw d = odotune::mc_draw(o, sc, r);
    EXPECT_EQ(d.seed, 40u + static_cast<unsigned>(r));
    for (double s : {d.truth_scale_l, d.truth_scale_r}) {
      EXPECT_GE(s, 0.98);
      EXPECT_LE(s, 1.02);
      ++seen[s];
    }
    const filters::PfCalibratorParams ranges;
    EXPECT_GE(d.dkf_initial.wheel_radius_right_m, ranges.wheel_radius_right_m.lo);
    EXPECT_LE(d.dkf_initial.wheel_radius_right_m, ranges.wheel_radius_right_m.hi);
    EXPECT_GE(d.dkf_initial.wheel_radius_left_m, ranges.wheel_radius_left_m.lo);
    EXPECT_LE(d.dkf_initial.wheel_radius_left_m, ranges.wheel_radius_left_m.hi);
    EXPECT_DOUBLE_EQ(d.dkf_initial.wheel_base_m, 0.65);
    // Deterministic.
    const odotune::McDraw again = odotune::mc_draw(o, sc, r);
    EXPECT_EQ(again.truth_scale_l, d.truth_scale_l);
    EXPECT_EQ(again.dkf_initial.wheel_radius_left_m, d.dkf_initial.wheel_radius_left_m);
    // The run's scenario: its seed and truth, other effects kept.
    const sim::Scenario rs = odotune::run_scenario(sc, d);
    EXPECT_EQ(rs.seed, d.seed);
    ASSERT_TRUE(rs.effects.radius_error.has_value());
    EXPECT_EQ(rs.effects.radius_error->scale_l, d.truth_scale_l);
    EXPECT_EQ(rs.effects.radius_error->scale_r, d.truth_scale_r);
    ASSERT_TRUE(rs.effects.wheel_base_error && rs.effects.radius_step);
    EXPECT_DOUBLE_EQ(rs.effects.radius_step->t, 10.0);
  }
  EXPECT_EQ(seen.size(), 40u);  // every draw different
}

TEST(StudyScenarioCheck, RejectsRobotsOutsideThePfRangesAndMissingSensors) {
  const odotune::StudyOptions o;
  EXPECT_NO_THROW(odotune::check_study_scenario(parsed(), o));
  sim::Scenario small = parsed();
  small.robot.wheel_radius_left_m = small.robot.wheel_radius_right_m = 0.05;
  try {
    odotune::check_study_scenario(small, o);
    ADD_FAILURE() << "accepted 0.05 m wheels";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("short_chair"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("outside the PF's initial range"), std::string::npos) << e.what();
  }
  sim::Scenario blind = parsed();
  blind.sensors.ext_velocity.enabled = false;
  EXPECT_THROW(odotune::check_study_scenario(blind, o), std::invalid_argument);
}

TEST(StudyConvergence, ReachedAndSettledPerPieceOfTheTruth) {
  // Truth 0.32 m both wheels until t = 10 s, then 0.31 m. Tolerance 0.5 %:
  // 1.6 mm before, 1.55 mm after.
  TruthSchedule truth;
  truth.from_s = {-INFINITY, 10.0};
  truth.params = {{0.32, 0.32, 0.65}, {0.31, 0.31, 0.65}};
  odotune::ParamTrace tr;
  // Estimates at t = 0.5, 1.0, ..., 20: R_R enters the band at 2 s, leaves at
  // 3 s, re-enters at 4 s for good; R_L is within from the start. After the
  // step both are off until 13 s (3 s after the change), then within.
  for (int i = 1; i <= 40; ++i) {
    const double t = 0.5 * i;
    double rr = 0.32, rl = 0.3205;
    if (t < 2.0 || (t >= 3.0 && t < 4.0)) rr = 0.325;
    if (t >= 10.0) rr = rl = t < 13.0 ? 0.32 : 0.3101;
    tr.t_s.push_back(t);
    tr.r_right_m.push_back(rr);
    tr.r_left_m.push_back(rl);
    tr.wheel_base_m.push_back(0.9);  // far off: must not matter
  }
  const auto c = odotune::radius_convergence(tr, truth, 0.5, 0.005);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_DOUBLE_EQ(c[0].reached_s, 2.0 - 0.5);
  EXPECT_DOUBLE_EQ(c[0].settled_s, 4.0 - 0.5);
  EXPECT_DOUBLE_EQ(c[1].reached_s, 3.0);
  EXPECT_DOUBLE_EQ(c[1].settled_s, 3.0);
  // Never within after the change → NaN.
  for (std::size_t i = 0; i < tr.t_s.size(); ++i)
    if (tr.t_s[i] >= 10.0) tr.r_left_m[i] = 0.33;
  const auto never = odotune::radius_convergence(tr, truth, 0.5, 0.005);
  EXPECT_TRUE(std::isnan(never[1].reached_s));
  EXPECT_TRUE(std::isnan(never[1].settled_s));
}

TEST(StudyFigureData, ResamplingBarsAreNormalisedByTheLargestMean) {
  odotune::ResamplingStudy s;
  for (auto r : odotune::table1_resamplers())
    for (auto p : odotune::table1_policies()) {
      odotune::ResamplingCell c;
      c.resampler = r;
      c.policy = p;
      s.cells.push_back(c);
    }
  // Errors (|R_R| + |R_L|)/2 per run: cell 0 → {1, 3} mm (mean 2), cell 5 → {4, 4} mm (mean 4).
  for (std::size_t i = 0; i < s.cells.size(); ++i) s.cells[i].runs = {{0.001, 0.001}, {0.001, 0.001}};
  s.cells[0].runs = {{0.001, 0.001}, {0.002, 0.004}};
  s.cells[5].runs = {{0.004, 0.004}, {0.003, 0.005}};
  for (auto& c : s.cells) c.ms_per_iteration = {1.0, 0.1, 2};
  s.cells[7].ms_per_iteration = {2.0, 0.5, 2};
  const odotune::ResamplingBars b = odotune::resampling_bars(s);
  ASSERT_EQ(b.groups.size(), 4u);
  ASSERT_EQ(b.series.size(), 3u);
  ASSERT_EQ(b.panels.size(), 2u);
  // Cell 5 = group 1 (multinomial), series 2 (every); cell 0 = group 0, series 0.
  EXPECT_EQ(b.groups[1], "multinomial");
  EXPECT_EQ(b.series[2], "every");
  EXPECT_DOUBLE_EQ(b.panels[0].mean[1][2], 1.0);
  EXPECT_DOUBLE_EQ(b.panels[0].mean[0][0], 0.5);
  EXPECT_NEAR(b.panels[0].sd[0][0], std::sqrt(2.0) * 0.001 / 0.004, 1e-12);  // sd of {1, 3} mm / 4 mm
  EXPECT_DOUBLE_EQ(b.panels[0].mean[2][0], 0.25);
  // Time: cell 7 = group 2 (residual), series 1 (max) is the slowest.
  EXPECT_DOUBLE_EQ(b.panels[1].mean[2][1], 1.0);
  EXPECT_DOUBLE_EQ(b.panels[1].sd[2][1], 0.25);
  EXPECT_DOUBLE_EQ(b.panels[1].mean[0][0], 0.5);
}

// The computation in-process: the numbers do not depend on the thread count.
TEST(StudyResampling, SameNumbersForOneAndTwoThreads) {
  odotune::StudyOptions o;
  o.runs = 2;
  o.seed = 11;
  o.pf_particles = 300;
  const sim::Scenario sc = parsed();
  o.threads = 1;
  const odotune::ResamplingStudy a = odotune::run_resampling_study(sc, o);
  o.threads = 2;
  const odotune::ResamplingStudy b = odotune::run_resampling_study(sc, o);
  ASSERT_EQ(a.cells.size(), 12u);
  EXPECT_EQ(without_timing(odotune::table1_runs_csv(a)), without_timing(odotune::table1_runs_csv(b)));
  EXPECT_EQ(a.threads_used, 1);
  EXPECT_EQ(b.threads_used, 2);
  // The every-step policy resamples at every iteration; the others less often.
  for (const auto& c : a.cells) {
    if (c.policy == filters::ResamplePolicy::every_step) {
      EXPECT_DOUBLE_EQ(c.resampled_fraction.mean, 1.0);
    } else {
      EXPECT_LT(c.resampled_fraction.mean, 1.0);
    }
  }
}

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
  EXPECT_NE(md.find("0.002623"), std::string::npos);      // the paper's Table I beside ours
  EXPECT_NE(md.find("Fariña"), std::string::npos);
  EXPECT_NE(md.find("--runs 2"), std::string::npos);      // the command that regenerates it

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
  const std::vector<std::string> methods = {"adaptive-pf", "dkf", "batch", "none"};
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
                               (*dir_ / "short.yaml").string() + " --out " + (*dir_ / "a_file" / "sub").string());
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
}  // namespace odotune

// End-to-end: tuning the particle-filter calibrators' settings with `tune --model pf-calib|adaptive-pf-calib`, in an experiment
// grid (experiments/calibration_smoke.yaml), and what report/export make of
// such a store.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <odotune/calibration/calibration_objective.h>
#include <odotune/formats/pf_config_yaml.h>
#include <odotune/results/store.h>

#include "support/cli_runner.h"

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;
using testing_support::reference_track;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::TempDir;

// The short simulated wheelchair drive kept in the repository (~42 s:
// R = 0.32 m, D = 0.65 m, 8800 counts/rev, encoders 100 Hz, v_ext/w_ext
// 10 Hz σ 0.02, ground truth 100 Hz, radius_error 0.99 / 1.012).
std::string wheelchair_track() { return std::string(ODOTUNE_SOURCE_DIR) + "/data/sim/wheelchair_short.csv"; }
std::string smoke_experiment() {
  return std::string(ODOTUNE_SOURCE_DIR) + "/experiments/calibration_smoke.yaml";
}

long newlines_in(const std::string& s) { return std::count(s.begin(), s.end(), '\n'); }

TEST(CliTuneCalibration, TheKeptTrackIsWhatItsScenarioSimulates) {
  TempDir tmp;
  const auto out = tmp / "w.csv";
  const auto r = run_cli("simulate " + std::string(ODOTUNE_SOURCE_DIR) +
                         "/scenarios/wheelchair_short.yaml -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(slurp(out), slurp(wheelchair_track()));
  EXPECT_LE(fs::file_size(out), 2u * 1024u * 1024u);
}

// One small adaptive-PF tune: 3 particles × (1 + 1) iterations.
std::string adaptive_tune_args(const fs::path& json_file, int threads, int seed = 4) {
  return fmt::format("tune --track {} --model adaptive-pf-calib --particles 3 --iterations 1 --seed {} "
                     "--pf-particles 400 --pf-seed 2 --resampler stratified --threads {} --json {}",
                     wheelchair_track(), seed, threads, json_file.string());
}

TEST(CliTuneCalibration, AdaptivePfJsonHasTheDocumentedKeysAndTunedNeverWorse) {
  TempDir tmp;
  const auto json_file = tmp / "t.json", cfg = tmp / "pf.yaml";
  const auto r = run_cli(adaptive_tune_args(json_file, 2) + " --config-out " + cfg.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("score"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("RMSE"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(slurp(json_file));
  for (const char* key :
       {"model",       "solver",           "seed",           "particles",    "iterations",    "calibrator",
        "params",      "param_units",      "default_params", "default_kept", "score_weights", "baseline_score",
        "tuned_score", "baseline_fitness", "tuned_fitness",  "baseline",     "tuned",         "improvement_pct",
        "evaluations", "seconds",          "termination",    "failures",     "tracks",        "convergence"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["model"], "adaptive-pf-calib");
  EXPECT_EQ(j["calibrator"]["method"], "adaptive-pf");
  EXPECT_EQ(j["calibrator"]["resampler"], "stratified");
  EXPECT_EQ(j["calibrator"]["policy"], "neff");
  EXPECT_EQ(j["calibrator"]["particles"], 400);
  EXPECT_EQ(j["calibrator"]["seed"], 2);
  EXPECT_EQ(j["evaluations"], 3 * 2);  // PSO: particles × (iterations + 1)
  EXPECT_EQ(j["failures"], 0);
  // The five settings with their units; the defaults are the paper's.
  const objectives::BoxSpace space = calibration::calibration_space();
  ASSERT_EQ(j["params"].size(), space.dim());
  for (const auto& p : space.params()) {
    ASSERT_TRUE(j["params"].contains(p.name)) << p.name;
    EXPECT_EQ(j["param_units"][p.name], p.unit);
  }
  EXPECT_EQ(j["default_params"]["neff_fraction"], 0.5);
  EXPECT_EQ(j["default_params"]["max_weight_ratio"], 10.0);
  EXPECT_EQ(j["default_params"]["alpha"], 1e-4);
  // The tuned settings are never worse than the defaults on the tuning track
  // (the default point is kept when the solver finds nothing better).
  EXPECT_LE(j["tuned_score"].get<double>(), j["baseline_score"].get<double>());
  EXPECT_EQ(j["tuned_fitness"], j["tuned_score"]);
  if (j["default_kept"].get<bool>()) {
    EXPECT_EQ(j["params"], j["default_params"]);
  }
  // Pose errors of the calibrated odometry, in metres, ordered MAE ≤ RMSE ≤ MAXE.
  for (const char* side : {"baseline", "tuned"}) {
    const auto& m = j[side];
    EXPECT_GT(m["rmse_m"].get<double>(), 0.0) << side;
    EXPECT_LT(m["rmse_m"].get<double>(), 5.0) << side;  // a 22 m drive
    EXPECT_LE(m["mae_m"].get<double>(), m["rmse_m"].get<double>()) << side;
    EXPECT_LE(m["rmse_m"].get<double>(), m["maxe_m"].get<double>()) << side;
  }
  ASSERT_EQ(j["tracks"].size(), 1u);
  EXPECT_EQ(j["tracks"][0]["track"], "wheelchair_short");
  EXPECT_TRUE(j["tracks"][0]["tuned"].contains("final_params"));
  EXPECT_TRUE(j["tracks"][0]["tuned"]["radius_error_pct"].is_number());  // a simulated track has truth

  // --config-out: the tuned settings, read back exactly by the reader.
  const odotune::formats::PfConfig c = odotune::formats::read_pf_config(cfg);
  EXPECT_EQ(c.method, calibration::CalibrationMethod::adaptive_pf);
  EXPECT_EQ(c.resampler, filters::Resampler::stratified);
  EXPECT_EQ(c.policy, filters::ResamplePolicy::neff);
  EXPECT_EQ(c.particles, 400);
  for (std::size_t i = 0; i < space.dim(); ++i)
    EXPECT_EQ(c.params[i], j["params"][space.params()[i].name].get<double>()) << space.params()[i].name;
}

TEST(CliTuneCalibration, SameSeedSameSettingsAnyThreadCount) {
  TempDir tmp;
  nlohmann::json runs[2];
  for (int k = 0; k < 2; ++k) {
    const auto json_file = tmp / fmt::format("r{}.json", k);
    const auto r = run_cli(adaptive_tune_args(json_file, 1 + k));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    runs[k] = nlohmann::json::parse(slurp(json_file));
    runs[k].erase("seconds");
  }
  EXPECT_EQ(runs[0]["params"], runs[1]["params"]);
  EXPECT_EQ(runs[0].dump(), runs[1].dump());
}

TEST(CliTuneCalibration, BadModelAndMisplacedOptionsAreOneLine) {
  auto r = run_cli("tune --track " + wheelchair_track() + " --model pf-calibrate");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(newlines_in(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("pf-calibrate"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("adaptive-pf-calib"), std::string::npos) << r.err;
  r = run_cli("tune --track " + wheelchair_track() + " --model pf-calib --mode 3");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(newlines_in(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--mode"), std::string::npos) << r.err;
  r = run_cli("tune --track " + reference_track(1) + " --model rq --resampler residual");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(newlines_in(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--resampler"), std::string::npos) << r.err;
  r = run_cli("tune --track " + wheelchair_track() + " --model pf-calib --policy sometimes");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(newlines_in(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("sometimes"), std::string::npos) << r.err;
}

// A 6 s drive without external velocities: refused by name, usable with
// velocities derived from the ground truth.
TEST(CliTuneCalibration, TrackWithoutExternalVelocitiesNeedsExtFromGt) {
  TempDir tmp;
  std::ofstream(tmp / "s.yaml")
      << "name: no_ext\nseed: 3\nrobot: {wheel_radius_left_m: 0.32, wheel_radius_right_m: 0.32, "
         "wheel_base_m: 0.65, ticks_per_rev: 8800}\n"
         "motion:\n  segments:\n    - stop: {duration_s: 0.5}\n"
         "    - arc: {radius_m: 1.0, angle_deg: 90, speed_m_s: 0.5}\n"
         "    - arc: {radius_m: 1.0, angle_deg: -90, speed_m_s: 0.5}\n"
         "sensors:\n  ext_velocity: {enabled: false}\n  aps: {enabled: false}\n"
         "  power: {enabled: false}\n  gyro: {enabled: false}\n"
         "effects:\n  radius_error: {scale_l: 0.99, scale_r: 1.012}\n";
  const auto sim = run_cli("simulate " + (tmp / "s.yaml").string() + " -o " + (tmp / "t.csv").string());
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::string base = "tune --track " + (tmp / "t.csv").string() +
                           " --model pf-calib --particles 2 --iterations 0 --pf-particles 200";
  const auto refused = run_cli(base);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_EQ(newlines_in(refused.err), 1) << refused.err;
  EXPECT_NE(refused.err.find("no_ext"), std::string::npos) << refused.err;
  const auto json_file = tmp / "j.json";
  const auto ok = run_cli(base + " --ext-from-gt 10 --json " + json_file.string());
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  const auto j = nlohmann::json::parse(slurp(json_file));
  EXPECT_EQ(j["calibrator"]["ext_from_gt_hz"], 10.0);
  EXPECT_EQ(j["model"], "pf-calib");
  EXPECT_EQ(j["calibrator"]["particles"], 200);
}

// ---------------------------------------------------------------------------
// Grid, report, export.

TEST(CliGridCalibration, SmokeExperimentStoresOneRunPerModelAndSeedAndReports) {
  TempDir tmp;
  const auto store = tmp / "s.sqlite";
  const auto g = run_cli("grid " + smoke_experiment() + " --store " + store.string() + " --threads 2");
  ASSERT_EQ(g.exit_code, 0) << g.err;
  const std::vector<results::RunRecord> runs = results::Store(store).runs();
  // 2 models × 1 track × 1 mode (calibrators: the first listed) × 2 seeds.
  ASSERT_EQ(runs.size(), 4u);
  std::set<std::string> cells;
  const objectives::BoxSpace space = calibration::calibration_space();
  for (const auto& r : runs) {
    cells.insert(fmt::format("{} {}", r.model, r.seed));
    EXPECT_EQ(r.track, "wheelchair_short");
    EXPECT_EQ(r.mode, 7);
    ASSERT_EQ(r.param_names.size(), space.dim());
    for (std::size_t i = 0; i < space.dim(); ++i) EXPECT_EQ(r.param_names[i], space.params()[i].name);
    EXPECT_TRUE(std::isfinite(r.best_fitness));
    EXPECT_GT(r.best_fitness, 0.0);
    EXPECT_GT(r.baseline.rmse_m, 0.0);
    EXPECT_GT(r.tuned.rmse_m, 0.0);
    EXPECT_LE(r.tuned.mae_m, r.tuned.rmse_m);
    EXPECT_LE(r.tuned.rmse_m, r.tuned.maxe_m);
    EXPECT_EQ(r.evaluations, 4 * 3);  // budget {particles: 4, iterations: 2}
    EXPECT_FALSE(r.convergence.empty());
    // best_fitness is the tuned score, never above the solver's own best.
    EXPECT_LE(r.best_fitness, r.convergence.back().best_fitness);
  }
  EXPECT_EQ(cells,
            (std::set<std::string>{"pf-calib 1", "pf-calib 2", "adaptive-pf-calib 1", "adaptive-pf-calib 2"}));
  // Both seeds of a model share the baseline (the default settings do not
  // depend on the solver's seed).
  for (const auto& a : runs)
    for (const auto& b : runs)
      if (a.model == b.model) {
        EXPECT_EQ(a.baseline.rmse_m, b.baseline.rmse_m);
      }

  // report: tables and heatmaps for the calibrators, no EKF trajectory replay.
  const auto out = tmp / "report";
  const auto rep = run_cli("report " + store.string() + " --out " + out.string());
  ASSERT_EQ(rep.exit_code, 0) << rep.err;
  for (const char* f :
       {"index.html", "table1_pf-calib.csv", "table1_adaptive-pf-calib.csv", "heatmap_pf-calib_rmse.svg",
        "heatmap_adaptive-pf-calib_rmse.svg", "boxplots.svg", "convergence_calibration_wheelchair_short.svg"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().rfind("trajectories_", 0), std::string::npos) << e.path();
  EXPECT_NE(slurp(out / "index.html").find("pf-calib"), std::string::npos);

  // export: a calibrator run is refused in one line.
  const auto ex = run_cli("export " + store.string() +
                          " --select model=adaptive-pf-calib --format odotune --out " +
                          (tmp / "x.yaml").string());
  EXPECT_NE(ex.exit_code, 0);
  EXPECT_EQ(newlines_in(ex.err), 1) << ex.err;
  EXPECT_NE(ex.err.find("calibrator"), std::string::npos) << ex.err;
  EXPECT_FALSE(fs::exists(tmp / "x.yaml"));
}

TEST(CliGridCalibration, CalibratorCellsUseTheFirstModeOnly) {
  TempDir tmp;
  std::ofstream(tmp / "e.yaml") << fmt::format(
      "format: odotune-experiment/1\nname: first-mode\nmodels: [pf-calib]\ntracks: [{}]\n"
      "modes: [3, 7]\nseeds: [5]\nsolver: pso\nbudget: {{particles: 2, iterations: 1}}\n"
      "calibration: {{particles: 200, policy: max, resampler: residual}}\nstore: s.sqlite\n",
      wheelchair_track());
  const auto g = run_cli("grid " + (tmp / "e.yaml").string());
  ASSERT_EQ(g.exit_code, 0) << g.err;
  const auto runs = results::Store(tmp / "s.sqlite").runs();
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].model, "pf-calib");
  EXPECT_EQ(runs[0].mode, 3);
  EXPECT_EQ(runs[0].seed, 5u);
}

TEST(CliGridCalibration, TrackUnusableForAListedModelIsOneLineNamingIt) {
  TempDir tmp;
  // The wheelchair track has no position fixes: the EKF model cannot use it.
  std::ofstream(tmp / "e.yaml") << fmt::format(
      "format: odotune-experiment/1\nmodels: [rq, pf-calib]\ntracks: [{}]\nmodes: [1]\nseeds: [1]\n"
      "store: s.sqlite\n",
      wheelchair_track());
  auto g = run_cli("grid " + (tmp / "e.yaml").string());
  EXPECT_NE(g.exit_code, 0);
  EXPECT_EQ(newlines_in(g.err), 1) << g.err;
  EXPECT_NE(g.err.find("wheelchair_short"), std::string::npos) << g.err;
  // A bad calibration key names file and line.
  std::ofstream(tmp / "b.yaml") << fmt::format(
      "format: odotune-experiment/1\nmodels: [adaptive-pf-calib]\ntracks: [{}]\nmodes: [1]\n"
      "seeds: [1]\ncalibration:\n  resampler: sometimes\n",
      wheelchair_track());
  g = run_cli("grid " + (tmp / "b.yaml").string());
  EXPECT_NE(g.exit_code, 0);
  EXPECT_EQ(newlines_in(g.err), 1) << g.err;
  EXPECT_NE(g.err.find("b.yaml:7:"), std::string::npos) << g.err;
  // An unknown model names the choices.
  std::ofstream(tmp / "m.yaml") << fmt::format(
      "format: odotune-experiment/1\nmodels: [pf]\ntracks: [{}]\nmodes: [1]\nseeds: [1]\n", wheelchair_track());
  g = run_cli("grid " + (tmp / "m.yaml").string());
  EXPECT_NE(g.exit_code, 0);
  EXPECT_NE(g.err.find("m.yaml:2:"), std::string::npos) << g.err;
  EXPECT_NE(g.err.find("pf-calib"), std::string::npos) << g.err;
}

}  // namespace
}  // namespace odotune::cli

// End-to-end: tuning the velocity-fusion UKF's noise with
// `tune --model ukf`, the odotune-ukf-config/1 round trip, an experiment grid
// with `models: [ukf]` (experiments/ukf_smoke.yaml), what report and export
// make of such a store, and the one-line errors.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <odotune/core/failure.h>
#include <odotune/formats/ukf_config_yaml.h>
#include <odotune/learned/fusion_input.h>
#include <odotune/learned/ukf_objective.h>
#include <odotune/results/store.h>
#include <odotune/tracks/track_io.h>

#include "support/cli_runner.h"

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::TempDir;

// The short simulated wheelchair drive kept in the repository (~42 s:
// R = 0.32 m, D = 0.65 m, 8800 counts/rev, encoders 100 Hz, v_ext/w_ext
// 10 Hz σ 0.02, ground truth 100 Hz, radius_error 0.99 / 1.012, no gyro);
// tests/cli/test_cli_tune_calibration.cpp checks it is what its scenario
// simulates.
std::string ukf_wheelchair_track() {
  return std::string(ODOTUNE_SOURCE_DIR) + "/data/sim/wheelchair_short.csv";
}
std::string ukf_smoke_experiment() { return std::string(ODOTUNE_SOURCE_DIR) + "/experiments/ukf_smoke.yaml"; }

long newline_count(const std::string& s) { return std::count(s.begin(), s.end(), '\n'); }

TEST(CliTuneUkf, TuneBeatsTheDefaultsAndTheConfigRoundTrips) {
  TempDir tmp;
  const auto json_file = tmp / "t.json", cfg = tmp / "ukf.yaml";
  const auto r = run_cli(
      fmt::format("tune --track {} --model ukf --mode 1 --particles 8 --iterations 5 --seed 3 --threads 2 "
                  "--json {} --config-out {}",
                  ukf_wheelchair_track(), json_file.string(), cfg.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("fusion UKF"), std::string::npos) << r.out;

  const auto j = nlohmann::json::parse(slurp(json_file));
  EXPECT_EQ(j["model"], "ukf");
  EXPECT_EQ(j["mode"], 1);
  EXPECT_EQ(j["evaluations"], 8 * 6);
  EXPECT_EQ(j["failures"], 0);
  EXPECT_EQ(j["fusion_rate_hz"], 10.0);
  // The static odometry does not know the radius error; the tuned noise
  // leans on the external velocities and beats the defaults.
  const double base = j["baseline"]["rmse_m"], tuned = j["tuned"]["rmse_m"];
  EXPECT_GT(base, 0.0);
  EXPECT_LT(tuned, base) << "tuned " << tuned << " vs defaults " << base;
  EXPECT_EQ(j["tuned_fitness"].get<double>(), tuned);  // mode 1: the fitness is the RMSE
  EXPECT_EQ(j["baseline_fitness"].get<double>(), base);
  const objectives::BoxSpace space = learned::ukf_space();
  ASSERT_EQ(j["params"].size(), space.dim());

  // The config: heavily commented, the tuned values bit for bit, and it
  // replays to the tuned RMSE.
  const std::string text = slurp(cfg);
  EXPECT_NE(text.find("format: odotune-ukf-config/1"), std::string::npos);
  EXPECT_GE(std::count(text.begin(), text.end(), '#'), 15) << text;
  const odotune::formats::UkfConfig c = odotune::formats::read_ukf_config(cfg);
  EXPECT_EQ(c.rate_hz, 10.0);
  for (std::size_t i = 0; i < space.dim(); ++i)
    EXPECT_EQ(c.params[i], j["params"][space.params()[i].name].get<double>()) << space.params()[i].name;
  const learned::FusionInput in = learned::build_fusion_input(tracks::read_track(ukf_wheelchair_track()));
  EXPECT_NEAR(learned::ukf_pose_errors(in, odotune::formats::apply_ukf_config(c)).rmse_m, tuned, 1e-12);

  // Same seed, one thread: the same result.
  const auto json1 = tmp / "t1.json";
  const auto r1 = run_cli(fmt::format(
      "tune --track {} --model ukf --mode 1 --particles 8 --iterations 5 --seed 3 --threads 1 --json {}",
      ukf_wheelchair_track(), json1.string()));
  ASSERT_EQ(r1.exit_code, 0) << r1.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(json1))["params"], j["params"]);
}

TEST(CliTuneUkf, ConfigReaderErrorsAreOneLineWithFileAndLine) {
  TempDir tmp;
  const auto path = tmp / "c.yaml";
  odotune::formats::UkfConfig good;
  good.params = learned::ukf_params_of(learned::UkfSettings{});
  odotune::formats::write_ukf_config(good, path);
  EXPECT_EQ(odotune::formats::read_ukf_config(path).params, good.params);

  auto error_of = [&](const std::string& text) {
    std::ofstream(path) << text;
    try {
      odotune::formats::read_ukf_config(path);
    } catch (const odotune::core::Failure& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string head = "format: odotune-ukf-config/1\nrate_hz: 10\nparams:\n";
  const std::string five = "  q_v_m2_s3: 0.05\n  q_w_rad2_s3: 0.1\n  odo_var_v: 0.001\n  odo_var_w: 0.001\n"
                           "  gyro_var: 4e-6\n";
  std::string e = error_of(head + five);
  EXPECT_NE(e.find("parameter 'ext_var_scale' is missing"), std::string::npos) << e;
  e = error_of(head + five + "  ext_var_scale: -1\n");
  EXPECT_NE(e.find("c.yaml:9:"), std::string::npos) << e;
  EXPECT_NE(e.find("ext_var_scale"), std::string::npos) << e;
  e = error_of(head + five + "  ext_var_scale: 1\n  q_x: 3\n");
  EXPECT_NE(e.find("unknown parameter 'q_x'"), std::string::npos) << e;
  e = error_of("format: odotune-pf-config/1\n");
  EXPECT_NE(e.find("odotune-ukf-config/1"), std::string::npos) << e;
  e = error_of("format: odotune-ukf-config/1\nrate_hz: 0\nparams: {}\n");
  EXPECT_NE(e.find("rate_hz"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

TEST(CliTuneUkf, BadInputIsOneLine) {
  TempDir tmp;
  // A track without ground truth: named, one line, nothing written.
  {
    tracks::TrackData d = tracks::read_track(ukf_wheelchair_track()).data();
    d.meta.name = "blind";
    for (tracks::Col c : {tracks::Col::gt_x, tracks::Col::gt_y, tracks::Col::gt_theta}) d.col(c).clear();
    tracks::write_track(tracks::Track(std::move(d)), tmp / "blind.csv");
  }
  const auto json_file = tmp / "x.json";
  auto r = run_cli(fmt::format("tune --track {} --model ukf --particles 2 --iterations 1 --json {}",
                               (tmp / "blind.csv").string(), json_file.string()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(newline_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("track 'blind': no ground truth"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(json_file));
  // A calibrator's option.
  r = run_cli(fmt::format("tune --track {} --model ukf --resampler stratified", ukf_wheelchair_track()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(newline_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--resampler"), std::string::npos) << r.err;
  // An unknown model lists ukf among the choices.
  r = run_cli(fmt::format("tune --track {} --model ukff", ukf_wheelchair_track()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("ukf"), std::string::npos) << r.err;
}

TEST(CliGridUkf, SmokeExperimentRunsStoresReportsAndExports) {
  TempDir tmp;
  const auto store = tmp / "s.sqlite";
  const auto g = run_cli("grid " + ukf_smoke_experiment() + " --store " + store.string() + " --threads 2");
  ASSERT_EQ(g.exit_code, 0) << g.err;
  const std::vector<results::RunRecord> runs = results::Store(store).runs();
  // 1 model × 1 track × 2 modes × 2 seeds: the UKF has fitness modes.
  ASSERT_EQ(runs.size(), 4u);
  std::set<std::string> cells;
  const objectives::BoxSpace space = learned::ukf_space();
  for (const auto& r : runs) {
    cells.insert(fmt::format("{} {} {}", r.model, r.mode, r.seed));
    EXPECT_EQ(r.track, "wheelchair_short");
    ASSERT_EQ(r.param_names.size(), space.dim());
    for (std::size_t i = 0; i < space.dim(); ++i) EXPECT_EQ(r.param_names[i], space.params()[i].name);
    EXPECT_EQ(r.evaluations, 8 * 6);  // budget {particles: 8, iterations: 5}
    EXPECT_EQ(r.diverged, 0);
    EXPECT_GT(r.baseline.rmse_m, 0.0);
    // Tuned on the scored track: never worse than the defaults for the mode.
    const double base = r.mode == 1 ? r.baseline.rmse_m
                                    : r.baseline.rmse_m + r.baseline.mae_m + r.baseline.maxe_m;
    const double tuned = r.mode == 1 ? r.tuned.rmse_m : r.tuned.rmse_m + r.tuned.mae_m + r.tuned.maxe_m;
    EXPECT_LE(tuned, base) << r.mode << " " << r.seed;
    EXPECT_NEAR(r.best_fitness, tuned, 1e-12);
    EXPECT_FALSE(r.convergence.empty());
  }
  EXPECT_EQ(cells, (std::set<std::string>{"ukf 1 1", "ukf 1 2", "ukf 7 1", "ukf 7 2"}));

  // A second grid on the same store runs nothing more.
  const auto again = run_cli("grid " + ukf_smoke_experiment() + " --store " + store.string());
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(results::Store(store).runs().size(), 4u);

  // report: the UKF's own table, no EKF trajectory replay.
  const auto out = tmp / "report";
  const auto rep = run_cli("report " + store.string() + " --out " + out.string());
  ASSERT_EQ(rep.exit_code, 0) << rep.err;
  for (const char* f : {"index.html", "table1_ukf.csv", "heatmap_ukf_rmse.svg", "boxplots.svg"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().rfind("trajectories_", 0), std::string::npos) << e.path();
  EXPECT_NE(slurp(out / "index.html").find("fusion UKF"), std::string::npos);

  // export --format odotune: the UKF config of the best run; it reads back.
  const auto x = tmp / "x.yaml";
  const auto ex = run_cli("export " + store.string() + " --select model=ukf,mode=1 --format odotune --out " +
                          x.string());
  ASSERT_EQ(ex.exit_code, 0) << ex.err;
  const odotune::formats::UkfConfig c = odotune::formats::read_ukf_config(x);
  const auto best = std::min_element(runs.begin(), runs.end(), [](const auto& a, const auto& b) {
    return (a.mode == 1 ? a.tuned.rmse_m : 1e9) < (b.mode == 1 ? b.tuned.rmse_m : 1e9);
  });
  EXPECT_EQ(c.params, best->params);
  // robot_localization has no mapping for the UKF: one line, no file.
  const auto y = tmp / "y.yaml";
  const auto er = run_cli("export " + store.string() +
                          " --select model=ukf --format robot_localization --out " + y.string());
  EXPECT_NE(er.exit_code, 0);
  EXPECT_EQ(newline_count(er.err), 1) << er.err;
  EXPECT_NE(er.err.find("no mapping for this model"), std::string::npos) << er.err;
  EXPECT_FALSE(fs::exists(y));
}

TEST(CliGridUkf, TrackWithoutGroundTruthIsOneLineNamingIt) {
  TempDir tmp;
  {
    tracks::TrackData d = tracks::read_track(ukf_wheelchair_track()).data();
    d.meta.name = "blind";
    for (tracks::Col c : {tracks::Col::gt_x, tracks::Col::gt_y, tracks::Col::gt_theta}) d.col(c).clear();
    tracks::write_track(tracks::Track(std::move(d)), tmp / "blind.csv");
  }
  std::ofstream(tmp / "e.yaml") << "format: odotune-experiment/1\nmodels: [ukf]\ntracks: [blind.csv]\n"
                                   "modes: [1]\nseeds: [1]\nbudget: {particles: 2, iterations: 1}\n"
                                   "store: s.sqlite\n";
  const auto g = run_cli("grid " + (tmp / "e.yaml").string());
  EXPECT_NE(g.exit_code, 0);
  EXPECT_EQ(newline_count(g.err), 1) << g.err;
  EXPECT_NE(g.err.find("track 'blind': no ground truth"), std::string::npos) << g.err;
}

}  // namespace
}  // namespace odotune::cli

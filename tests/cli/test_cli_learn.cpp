// odotune learn train|eval|retrain and odotune study learned, end to end on
// short simulated wheelchair drives (tens of seconds instead of minutes) and
// few Ceres iterations, so that the whole file runs in seconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include <odotune/results/learned_model_json.h>
#include <odotune/tracks/odometry_input.h>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::TempDir;

// The wheelchair of scenarios/wheelchair_learn.yaml (0.32 m wheels, 8800
// counts, D = 0.65 m, motor power) on a short drive. Effects the kinematic
// model lacks: radius_error and speed_radius (tyres grow with speed).
std::string chair(const std::string& name, int seed, const std::string& segments, const std::string& more = "",
                  bool ground_truth = true) {
  return "name: " + name + "\nseed: " + std::to_string(seed) +
         "\nrobot: {wheel_radius_left_m: 0.32, wheel_radius_right_m: 0.32, wheel_base_m: 0.65, ticks_per_rev: 8800,\n"
         "        mass_kg: 130.0, yaw_inertia_kg_m2: 18.0, wheel_inertia_kg_m2: 0.4, viscous_friction_nm_s: 0.5,\n"
         "        coulomb_friction_nm: 3.0, torque_constant_nm_per_a: 8.0, coil_resistance_ohm: 0.3}\n"
         "motion:\n  max_accel_m_s2: 0.45\n  max_angular_accel_rad_s2: 1.2\n  segments:\n" +
         segments +
         "sensors:\n  power: {rate_hz: 100, sigma_w: 0.5}\n  aps: {enabled: false}\n"
         "  ext_velocity: {rate_hz: 10, sigma_v_m_s: 0.02, sigma_w_rad_s: 0.02}\n"
         "  ground_truth: {enabled: " +
         (ground_truth ? "true" : "false") +
         "}\n"
         "effects:\n  radius_error: {scale_l: 1.03, scale_r: 0.985}\n  speed_radius: {c: 0.05}\n" +
         more;
}

const char* const kLearnRoute = "    - stop: {duration_s: 1}\n"
                                "    - straight: {distance_m: 4, speed_m_s: 0.5}\n"
                                "    - arc: {radius_m: 1.5, angle_deg: 90, speed_m_s: 0.6}\n"
                                "    - straight: {distance_m: 6, speed_m_s: 1.0}\n"
                                "    - arc: {radius_m: 1.0, angle_deg: -120, speed_m_s: 0.5}\n"
                                "    - straight: {distance_m: 3, speed_m_s: 0.8}\n"
                                "    - spin: {angle_deg: 90, rate_deg_s: 40}\n"
                                "    - straight: {distance_m: 3, speed_m_s: 0.6}\n"
                                "    - arc: {radius_m: 2.0, angle_deg: -60, speed_m_s: 0.9}\n"
                                "    - arc: {radius_m: 1.2, angle_deg: 100, speed_m_s: 0.7}\n"
                                "    - straight: {distance_m: 4, speed_m_s: 0.4}\n"
                                "    - stop: {duration_s: 1}\n";

// The learning route and its mirror image (turns the other way): ~100 s.
std::string learn_route() {
  std::string mirrored = kLearnRoute;
  for (std::size_t at = 0; (at = mirrored.find("angle_deg: ", at)) != std::string::npos; at += 11) {
    if (mirrored[at + 11] == '-')
      mirrored.erase(at + 11, 1);
    else
      mirrored.insert(at + 11, "-");
  }
  return kLearnRoute + mirrored;
}

const char* const kEvalRoute = "    - stop: {duration_s: 1}\n"
                               "    - straight: {distance_m: 3, speed_m_s: 0.7}\n"
                               "    - arc: {radius_m: 1.2, angle_deg: -90, speed_m_s: 0.55}\n"
                               "    - straight: {distance_m: 5, speed_m_s: 0.9}\n"
                               "    - arc: {radius_m: 1.8, angle_deg: 120, speed_m_s: 0.7}\n"
                               "    - straight: {distance_m: 3, speed_m_s: 0.5}\n"
                               "    - stop: {duration_s: 1}\n";

const char* const kSlipEpisodes = "slip_episodes:\n"
                                  "  - {kind: hold, wheel: left, t0_s: 6, t1_s: 8.5, s: 0.5, brake_nm: 14}\n"
                                  "  - {kind: spin, wheel: right, t0_s: 14, t1_s: 16.5, s: 0.6}\n";

class LearnCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TempDir>("learn");
    const auto sim = [](const std::string& name, const std::string& yaml) {
      const fs::path y = *dir_ / (name + ".yaml");
      std::ofstream(y) << yaml;
      const auto r = run_cli("simulate " + y.string() + " -o " + (*dir_ / (name + ".csv")).string());
      ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    };
    sim("learn", chair("learn", 3, learn_route()));
    sim("eval", chair("eval", 4, kEvalRoute));
    sim("step", chair("step", 5, learn_route(), "  radius_step: {t: 30, scale_l: 0.96, scale_r: 1.0}\n"));
    sim("slip", chair("slip", 6, kEvalRoute) + kSlipEpisodes);
    sim("nogt", chair("nogt", 7, kEvalRoute, "", false));
    const auto r = run_cli("learn train --track " + track("learn") + " --slip-track " + track("slip") +
                           " --model-out " + (*dir_ / "model.json").string() +
                           " --iterations 60 --slip-iterations 5 --seed 1 --target velocity");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    train_out_ = r.out;
  }
  static void TearDownTestSuite() { dir_.reset(); }

  static std::string track(const std::string& name) { return (*dir_ / (name + ".csv")).string(); }
  static std::string model() { return (*dir_ / "model.json").string(); }

  static std::unique_ptr<TempDir> dir_;
  static std::string train_out_;
};
std::unique_ptr<TempDir> LearnCli::dir_;
std::string LearnCli::train_out_;

json read_json(const fs::path& p) { return json::parse(slurp(p)); }

std::size_t lines(const std::string& s) {
  std::size_t n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

// The track at `from` without the named columns (each must be there), written to `to`.
void copy_track_without(const std::string& from, const fs::path& to, const std::vector<std::string>& columns) {
  std::ifstream in(from);
  std::ofstream out(to);
  std::vector<std::size_t> drop;  // column indices, last first
  bool header = true;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind('#', 0) == 0) {
      out << line << "\n";
      continue;
    }
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    if (header) {
      for (std::size_t i = cells.size(); i-- > 0;)
        if (std::find(columns.begin(), columns.end(), cells[i]) != columns.end()) drop.push_back(i);
      ASSERT_EQ(drop.size(), columns.size()) << line;
      header = false;
    }
    for (std::size_t i : drop) cells.erase(cells.begin() + static_cast<std::ptrdiff_t>(i));
    for (std::size_t i = 0; i < cells.size(); ++i) out << (i ? "," : "") << cells[i];
    out << "\n";
  }
}

// A failed command: non-zero exit, exactly one line on stderr mentioning `needle`.
void expect_one_line_error(const testing_support::CliResult& r, const std::string& needle) {
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
}

TEST_F(LearnCli, TrainWritesAModelThatLoads) {
  const results::LearnedModelFile m = results::read_learned_model(model());
  ASSERT_TRUE(m.detector.has_value());
  std::string why;
  EXPECT_TRUE(m.odometry.IsValid(&why)) << why;
  EXPECT_TRUE(m.detector->IsValid(&why)) << why;
  EXPECT_EQ(m.odometry.ticks_per_rev, 8800.0);
  EXPECT_EQ(m.odometry.rate_hz, 10.0);
  EXPECT_EQ(m.provenance.tracks, std::vector<std::string>{"learn"});
  EXPECT_EQ(m.provenance.slip_tracks, std::vector<std::string>{"slip"});
  EXPECT_EQ(m.provenance.seed, 1u);
  EXPECT_GT(m.provenance.odometry.train_windows, m.provenance.odometry.validation_windows);
  EXPECT_GT(m.provenance.odometry.validation_windows, 0u);
  EXPECT_GT(m.provenance.odometry.v.iterations, 0);
  EXPECT_NE(train_out_.find("V net: MAE"), std::string::npos) << train_out_;
  EXPECT_NE(train_out_.find("kinematic odometry"), std::string::npos) << train_out_;
}

TEST_F(LearnCli, EvalHasBothBlocksAndLearnedBeatsKinematic) {
  const fs::path out = *dir_ / "eval.json";
  const fs::path csv = *dir_ / "eval-steps.csv";  // not the track eval.csv
  const auto r = run_cli("learn eval --track " + track("eval") + " --model " + model() + " --json " +
                         out.string() + " --csv " + csv.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = read_json(out);
  EXPECT_EQ(j.at("track"), "eval");
  for (const char* block : {"learned", "kinematic"})
    for (const char* key : {"v_mae", "w_mae", "v_rmse", "w_rmse", "v_r2", "w_r2", "pos_mae_m", "pos_rmse_m",
                            "pos_r2", "theta_mae_rad", "theta_rmse_rad"}) {
      ASSERT_TRUE(j.at(block).contains(key)) << block << "." << key;
      ASSERT_TRUE(j[block][key].is_number()) << block << "." << key << " = " << j[block][key];
      EXPECT_TRUE(std::isfinite(j[block][key].get<double>())) << block << "." << key;
    }
  // The radius error and the speed-dependent radius are learned, not modelled.
  EXPECT_LT(j["learned"]["v_mae"].get<double>(), j["kinematic"]["v_mae"].get<double>());
  EXPECT_LT(j["learned"]["w_mae"].get<double>(), j["kinematic"]["w_mae"].get<double>());
  EXPECT_LT(j["learned"]["pos_rmse_m"].get<double>(), j["kinematic"]["pos_rmse_m"].get<double>());
  // MAE ≤ RMSE for any series.
  for (const char* block : {"learned", "kinematic"})
    EXPECT_LE(j[block]["v_mae"].get<double>(), j[block]["v_rmse"].get<double>());
  const std::string c = slurp(csv);
  EXPECT_EQ(c.rfind("t_s,v_true,w_true,v_learned", 0), 0u);
  EXPECT_GT(lines(c), 100u);
}

// A model whose net did not beat the kinematics in its training says so on
// eval's first line; an unknown --target is refused by name.
TEST_F(LearnCli, ANetWithoutGainIsSaidFirst) {
  json m = read_json(model());
  EXPECT_EQ(m["odometry"]["target"], "velocity");
  m["odometry"]["target"] = "correction";
  m["odometry"]["features"] = "both";
  m["odometry"]["w_beats_kinematic"] = false;
  const fs::path flagged = *dir_ / "flagged.json";
  std::ofstream(flagged) << m.dump();
  const auto r = run_cli("learn eval --track " + track("eval") + " --model " + flagged.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("note: the model's W net did not beat the kinematic odometry", 0), 0u) << r.out;
  const auto plain = run_cli("learn eval --track " + track("eval") + " --model " + model());
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_EQ(plain.out.find("note:"), std::string::npos) << plain.out;
  const fs::path out = *dir_ / "target.json";
  expect_one_line_error(
      run_cli("learn train --track " + track("learn") + " --target residual --model-out " + out.string()),
      "--target");
  EXPECT_FALSE(fs::exists(out));
}

// Correction nets on the simulator's commands (the robot's lag and its
// unequal wheels to learn): chosen by cross-validation over two drives, the
// model records its input and the choice, and eval reads a track's
// commands; a model on commands refuses a track without them, in one line.
TEST_F(LearnCli, CorrectionNetsOnCommandsAreCrossValidatedAndRecorded) {
  const fs::path cmd = *dir_ / "commands.json";
  const auto r = run_cli(
      "learn train --track " + track("learn") + " --track " + track("step") +
      " --input commands --units 3 --windows 10 --decays 0 --features channel,both --iterations 20 "
      "--model-out " +
      cmd.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("correction nets on commands"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cross-validation over 2 recordings in 2 folds, 2 candidate settings"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("each fold judged by nets trained without it"), std::string::npos) << r.out;
  const results::LearnedModelFile m = results::read_learned_model(cmd);
  EXPECT_EQ(m.odometry.input, tracks::OdometryInput::commands);
  EXPECT_EQ(m.odometry.target, learned::LearnedTarget::correction);
  EXPECT_EQ(m.odometry.v_net.units(), 3);
  ASSERT_TRUE(m.provenance.selection.has_value());
  EXPECT_EQ(m.provenance.selection->at("folds"), 2);
  EXPECT_EQ(m.provenance.selection->at("tried").size(), 2u);
  EXPECT_NE(m.provenance.created_by.find("--input commands"), std::string::npos) << m.provenance.created_by;
  const fs::path out = *dir_ / "commands-eval.json";
  const auto e = run_cli("learn eval --track " + track("eval") + " --model " + cmd.string() + " --json " +
                         out.string());
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const json j = read_json(out);
  EXPECT_EQ(j.at("input"), "commands");
  EXPECT_TRUE(j.at("learned").at("pos_rmse_60s_m").is_number());
  // The eval track without its commands.
  const fs::path wheels = *dir_ / "wheels_only.csv";
  copy_track_without(track("eval"), wheels, {"v_cmd", "w_cmd"});
  expect_one_line_error(run_cli("learn eval --track " + wheels.string() + " --model " + cmd.string()), "v_cmd");
}

// With position fixes on the track, eval also fuses each odometry with them
// (the fixes' σ given for fixes without variances; with them, none needed); --from scores the
// second part only.
TEST_F(LearnCli, EvalFusesFixesAndScoresAPart) {
  const fs::path fixed = *dir_ / "eval-fixes.csv", out = *dir_ / "fused.json";
  ASSERT_EQ(
      run_cli("fixes " + track("eval") + " -o " + fixed.string() + " --rate-hz 1 --sigma-m 0.1 --no-variances")
          .exit_code,
      0);
  const auto r = run_cli("learn eval --track " + fixed.string() + " --model " + model() +
                         " --fix-sigma-m 0.1 --from 10 --json " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("fused with "), std::string::npos) << r.out;
  const json j = read_json(out);
  ASSERT_TRUE(j.contains("fused")) << j.dump(1);
  EXPECT_GT(j["fused"]["fixes"].get<int>(), 5);
  EXPECT_LT(j["fused"]["kinematic"]["pos_rmse_m"].get<double>(), j["kinematic"]["pos_rmse_m"].get<double>());
  EXPECT_GE(j.at("span_s")[0].get<double>(), 10.0);
  const auto no_sigma = run_cli("learn eval --track " + fixed.string() + " --model " + model());
  ASSERT_EQ(no_sigma.exit_code, 0) << no_sigma.err;
  EXPECT_NE(no_sigma.out.find("not fused with the track's fixes"), std::string::npos) << no_sigma.out;
  // Fixes with their variances (odotune fixes' default) are fused without --fix-sigma-m.
  const fs::path with_var = *dir_ / "eval-fixes-var.csv";
  ASSERT_EQ(
      run_cli("fixes " + track("eval") + " -o " + with_var.string() + " --rate-hz 1 --sigma-m 0.1").exit_code,
      0);
  const auto own = run_cli("learn eval --track " + with_var.string() + " --model " + model());
  ASSERT_EQ(own.exit_code, 0) << own.err;
  EXPECT_NE(own.out.find("fused with "), std::string::npos) << own.out;
  expect_one_line_error(
      run_cli("learn eval --track " + fixed.string() + " --model " + model() + " --from 1000"),
      "--from/--until");
}

// Retraining on a drive without external velocities takes them from its
// ground truth (--ext-from-gt), and on its first part only (--until).
TEST_F(LearnCli, RetrainTakesTheGroundTruthAsItsReference) {
  const fs::path m2 = *dir_ / "ref-retrained.json", out = *dir_ / "ref-retrain.json";
  const fs::path noext = *dir_ / "step-noext.csv";
  copy_track_without(track("step"), noext, {"v_ext", "w_ext", "v_ext_var", "w_ext_var"});
  expect_one_line_error(
      run_cli("learn retrain --track " + noext.string() + " --model " + model() + " --static-covariance"),
      "--ext-from-gt");
  const auto r = run_cli("learn retrain --track " + noext.string() + " --model " + model() +
                         " --static-covariance --ext-from-gt 10 --until 60 --model-out " + m2.string() +
                         " --json " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = read_json(out);
  for (const json& e : j.at("retrains")) EXPECT_LT(e.at("t_s").get<double>(), 60.0);
  EXPECT_NE(results::read_learned_model(m2).provenance.created_by.find("--until 60"), std::string::npos);
}

TEST_F(LearnCli, RetrainWritesEventsAndAModel) {
  const fs::path out = *dir_ / "retrain.json", m2 = *dir_ / "model2.json";
  const auto r = run_cli("learn retrain --track " + track("step") + " --model " + model() + " --model-out " +
                         m2.string() + " --json " + out.string() + " --every 40 --iterations 10");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = read_json(out);
  ASSERT_TRUE(j.at("retrains").is_array());
  ASSERT_GE(j["retrains"].size(), 1u) << j.dump(1);
  double last_t = -1.0;
  for (const json& e : j["retrains"]) {
    EXPECT_GT(e.at("t_s").get<double>(), last_t);
    last_t = e["t_s"].get<double>();
    EXPECT_GE(e.at("ms").get<double>(), 0.0);
    EXPECT_TRUE(e.at("v").at("cost_after").is_number());
  }
  for (const char* block : {"with_retraining", "without_retraining"})
    for (const char* part : {"odometry", "filter"})
      EXPECT_TRUE(std::isfinite(j.at(block).at(part).at("w_mae").get<double>())) << block << "." << part;
  const results::LearnedModelFile m = results::read_learned_model(m2);
  EXPECT_EQ(m.provenance.retrains, static_cast<int>(j["retrains"].size()));
  EXPECT_EQ(m.provenance.retrain_tracks, std::vector<std::string>{"step"});
  const results::LearnedModelFile before = results::read_learned_model(model());
  EXPECT_FALSE(m.odometry.w_net == before.odometry.w_net);  // the nets were refitted
  // The standardisation is kept.
  ASSERT_EQ(m.odometry.w_net.units(), before.odometry.w_net.units());
  m.odometry.w_net.visit([&](const auto& a) {
    before.odometry.w_net.visit([&](const auto& b) {
      if constexpr (std::is_same_v<decltype(a), decltype(b)>) {
        EXPECT_EQ(a.input_mean, b.input_mean);
      }
    });
  });
}

TEST_F(LearnCli, BadInputsFailWithOneLineAndNoOutput) {
  const fs::path out = *dir_ / "bad.json";
  // A missing track file.
  expect_one_line_error(run_cli("learn eval --track " + (*dir_ / "none.csv").string() + " --model " + model() +
                                " --json " + out.string()),
                        "none.csv");
  EXPECT_FALSE(fs::exists(out));
  // A model file that is not JSON, and one with a bad field.
  const fs::path garbage = *dir_ / "garbage.json";
  std::ofstream(garbage) << "{ not json";
  expect_one_line_error(run_cli("learn eval --track " + track("eval") + " --model " + garbage.string() +
                                " --json " + out.string()),
                        "garbage.json");
  EXPECT_FALSE(fs::exists(out));
  json m = read_json(model());
  m["odometry"]["rate_hz"] = -10;
  const fs::path bad_model = *dir_ / "bad_model.json";
  std::ofstream(bad_model) << m.dump();
  expect_one_line_error(run_cli("learn eval --track " + track("eval") + " --model " + bad_model.string() +
                                " --json " + out.string()),
                        "odometry.rate_hz");
  EXPECT_FALSE(fs::exists(out));
  // A track without ground truth.
  expect_one_line_error(
      run_cli("learn eval --track " + track("nogt") + " --model " + model() + " --json " + out.string()),
      "ground truth");
  EXPECT_FALSE(fs::exists(out));
  expect_one_line_error(run_cli("learn train --track " + track("nogt") + " --model-out " + out.string()),
                        "ground truth");
  EXPECT_FALSE(fs::exists(out));
  // Retraining with the model's detector on a track without motor power.
  const fs::path nopower = *dir_ / "nopower.csv";
  {
    const fs::path y = *dir_ / "nopower.yaml";
    std::ofstream(y) << chair("nopower", 8, kEvalRoute);
    std::string yaml = slurp(y);
    yaml.replace(yaml.find("power: {rate_hz: 100, sigma_w: 0.5}"), 35, "power: {enabled: false}");
    std::ofstream(y) << yaml;
    ASSERT_EQ(run_cli("simulate " + y.string() + " -o " + nopower.string()).exit_code, 0);
  }
  expect_one_line_error(run_cli("learn retrain --track " + nopower.string() + " --model " + model() +
                                " --json " + out.string() + " --model-out " + (*dir_ / "m3.json").string()),
                        "motor power");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(*dir_ / "m3.json"));
  // An output folder that does not exist.
  expect_one_line_error(run_cli("learn train --track " + track("learn") + " --model-out " +
                                (*dir_ / "no_dir" / "m.json").string()),
                        "does not exist");
}

// ---------------------------------------------------------------- study learned

struct Study {
  std::string md1, md2, md3, csv1, csv3;
  json results;
};

std::string study_args(const fs::path& dir, const fs::path& out) {
  const auto f = [&](const char* n) { return (dir / (std::string(n) + ".yaml")).string(); };
  return "study learned --out " + out.string() + " --seed 3 --iterations 8 --retrain-iterations 2 --every 40" +
         " --learn-scenario " + f("learn") + " --eval-scenario " + f("eval") + " --step-scenario " + f("step") +
         " --slip-scenario " + f("slip") + " --slip-eval-scenario " + f("slip");
}

// The value of `key` (e.g. "mae") of `column` in a results.json errors block.
double value(const json& errors, const char* column, const char* key) {
  const json& v = errors.at(column).at(key);
  return v.is_null() ? NAN : v.get<double>();
}

// CSV row "method,metric,V,W,XY,θ" → the four numbers.
std::vector<double> csv_row(const std::string& csv, const std::string& method, const std::string& metric) {
  std::stringstream ss(csv);
  std::string line;
  while (std::getline(ss, line))
    if (line.rfind(method + "," + metric + ",", 0) == 0) {
      std::vector<double> out;
      std::stringstream ls(line.substr(method.size() + metric.size() + 2));
      std::string f;
      while (std::getline(ls, f, ',')) out.push_back(f.empty() ? NAN : std::stod(f));
      while (out.size() < 4) out.push_back(NAN);
      return out;
    }
  ADD_FAILURE() << "no row " << method << "," << metric << " in\n" << csv;
  return {NAN, NAN, NAN, NAN};
}

TEST_F(LearnCli, StudyLearnedTablesAreRecomputableAndDeterministic) {
  const fs::path a = *dir_ / "study_a", b = *dir_ / "study_b";
  const auto ra = run_cli(study_args(dir_->path(), a));
  ASSERT_EQ(ra.exit_code, 0) << ra.err;
  const auto rb = run_cli(study_args(dir_->path(), b));
  ASSERT_EQ(rb.exit_code, 0) << rb.err;
  // Determinism: everything but timing is in results.json.
  EXPECT_EQ(slurp(a / "results.json"), slurp(b / "results.json"));

  for (const char* f :
       {"table1.md", "table1.csv", "table2.md", "table2.csv", "table3.md", "table3.csv", "results.json",
        "model.json", "fig_slip_variance.png", "fig_slip_variance.svg", "fig_retraining_error.png",
        "fig_retraining_error.svg", "fig_paths.png", "fig_paths.svg"})
    EXPECT_TRUE(fs::exists(a / f)) << f;
  const std::string md1 = slurp(a / "table1.md"), md2 = slurp(a / "table2.md"), md3 = slurp(a / "table3.md");
  for (const char* h : {"V (m/s)", "W (rad/s)", "X-Y (m)", "θ (rad)"}) {
    EXPECT_NE(md1.find(h), std::string::npos) << h;
    EXPECT_NE(md3.find(h), std::string::npos) << h;
  }
  for (const char* row : {"LSTM odometry", "Traditional odometry", "MAE", "RMSE", "R²"})
    EXPECT_NE(md1.find(row), std::string::npos) << row;
  for (const char* row : {"LSTM retraining", "LSTM no retraining", "Traditional odometry",
                          "After the radius change", "Whole track", "retrains"})
    EXPECT_NE(md2.find(row), std::string::npos) << row;
  for (const char* row : {"LSTM odometry + variable covariance", "Traditional odometry + static covariance",
                          "LSTM odometry + static covariance", "NEES_Odom", "NEES_Filter"})
    EXPECT_NE(md3.find(row), std::string::npos) << row;

  // The tables' numbers are results.json's.
  const json j = read_json(a / "results.json");
  const std::string csv1 = slurp(a / "table1.csv"), csv3 = slurp(a / "table3.csv");
  for (const json& row : j.at("table1").at("rows")) {
    const std::string method = row.at("method");
    for (const char* metric : {"mae", "rmse"}) {
      const std::vector<double> c = csv_row(csv1, method, metric);
      EXPECT_DOUBLE_EQ(c[0], value(row["errors"], "v", metric)) << method << " " << metric;
      EXPECT_DOUBLE_EQ(c[1], value(row["errors"], "w", metric)) << method << " " << metric;
      EXPECT_DOUBLE_EQ(c[2], value(row["errors"], "xy", metric)) << method << " " << metric;
      EXPECT_DOUBLE_EQ(c[3], value(row["errors"], "theta", metric)) << method << " " << metric;
    }
    const std::vector<double> r2 = csv_row(csv1, method, "r2");
    EXPECT_DOUBLE_EQ(r2[0], value(row["errors"], "v", "r2"));
    EXPECT_TRUE(std::isnan(r2[3])) << "θ has no R²";
    // MAE ≤ RMSE.
    EXPECT_LE(value(row["errors"], "xy", "mae"), value(row["errors"], "xy", "rmse"));
  }
  ASSERT_EQ(j.at("table3").at("rows").size(), 3u);
  for (const json& row : j["table3"]["rows"]) {
    const std::string method = row.at("method");
    const std::vector<double> odom = csv_row(csv3, method, "nees_odom");
    const std::vector<double> filt = csv_row(csv3, method, "nees_filter");
    EXPECT_DOUBLE_EQ(odom[0], value(row["odometry"], "v", "nees"));
    EXPECT_DOUBLE_EQ(odom[1], value(row["odometry"], "w", "nees"));
    EXPECT_DOUBLE_EQ(filt[1], value(row["filter"], "w", "nees"));
    EXPECT_GT(filt[1], 0.0);
  }
  ASSERT_EQ(j.at("table2").at("rows").size(), 3u);
  EXPECT_EQ(j["table2"]["change_t_s"].get<double>(), 30.0);
  // The kinematic odometry does not change with the filter: its errors after
  // the change are over fewer samples than over the whole track.
  const json& kin = j["table2"]["rows"][2];
  EXPECT_LT(kin["after_change"]["v"]["samples"].get<int>(), kin["whole"]["v"]["samples"].get<int>());
}

TEST_F(LearnCli, StudyRejectsABadScenarioBeforeCreatingTheFolder) {
  const fs::path out = *dir_ / "study_bad";
  // The step scenario without a radius change.
  std::string args = study_args(dir_->path(), out);
  args.replace(args.find("step.yaml"), 9, "eval.yaml");
  expect_one_line_error(run_cli(args), "radius_step");
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace odotune::cli

// calibrate --controller-out and diagnose --controller-out end to end: every
// calibration method exports its final estimate, inconsistent flags are
// refused by name before any work and leave nothing behind, and a round trip
// (calibrate, apply the file's multipliers to the nominal geometry, calibrate
// again) leaves nothing to correct. The robot is the wheelchair of the
// calibration tests (R = 0.32 m, D = 0.65 m, 8800 counts per revolution) with
// R_L × 0.99, R_R × 1.012 and D × 1.02.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <odotune/tracks/track_io.h>

#include "diagnose/sim_track.h"
#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::TempDir;
using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr double kRNom = 0.32, kDNom = 0.65;
constexpr double kControllerScaleL = 0.99, kControllerScaleR = 1.012, kScaleD = 1.02;

// The misaligned wheelchair on the laps of diagnose/sim_track.h, ground truth
// at 100 Hz with σ 1 mm (so the pose fit has a finite precision), 10 Hz
// external velocities.
std::string write_chair(const TempDir& dir, const std::string& name, double duration_s, bool ext = true) {
  testing_support::SimTrackOptions so;
  so.duration_s = duration_s;
  so.wheel_radius_left_m = so.wheel_radius_right_m = kRNom;
  so.wheel_base_m = kDNom;
  so.ticks_per_rev = 8800;
  so.gyro_rate_hz = 0.0;
  so.gt_sigma_m = 0.001;
  so.effects = {"radius_error:scale_l=0.99,scale_r=1.012", "wheel_base_error:scale=1.02"};
  so.seed = 5;
  sim::Scenario sc = testing_support::sim_scenario(so);
  sc.name = name;
  sc.sensors.ext_velocity.enabled = ext;
  sc.sensors.ext_velocity.rate_hz = 10.0;
  const std::string path = (dir.path() / (name + ".csv")).string();
  tracks::write_track(sim::simulate(sc), path);
  return path;
}

// A ROS 2 file's parameters (the controller named diff_drive_controller).
std::map<std::string, double> ros2_params(const fs::path& file) {
  const YAML::Node p = YAML::LoadFile(file.string())["diff_drive_controller"]["ros__parameters"];
  std::map<std::string, double> out;
  for (const auto& kv : p) out[kv.first.as<std::string>()] = kv.second.as<double>();
  EXPECT_EQ(out.size(), 5u) << slurp(file);
  return out;
}

// The geometry a ROS controller runs with these parameters:
// wheel_radius × left/right multiplier, wheel_separation × its multiplier.
struct Effective {
  double left_m, right_m, base_m;
};
Effective effective(const std::map<std::string, double>& p) {
  return {p.at("wheel_radius") * p.at("left_wheel_radius_multiplier"),
          p.at("wheel_radius") * p.at("right_wheel_radius_multiplier"),
          p.at("wheel_separation") * p.at("wheel_separation_multiplier")};
}

std::size_t line_count(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

class CliController : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("controller");
    track_ = write_chair(*dir_, "chair", 60.0);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static TempDir* dir_;
  static std::string track_;
};
TempDir* CliController::dir_ = nullptr;
std::string CliController::track_;

// Online methods export the estimate after the last track, as --config-out
// does; the file's geometry is --config-out's to the file's rounding (6
// decimals on a multiplier of a 0.32 m wheel: 0.16 µm; metres to 0.05 µm).
TEST_F(CliController, EveryMethodExportsItsFinalEstimateForEveryKind) {
  TempDir tmp;
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"batch", "ros2_control"},
      {"batch-velocity", "ros1"},
      {"dkf", "gazebo"},
      {"pf --particles 500 --threads 1", "ros2_control --controller-form absolute"},
      {"adaptive-pf --particles 500 --threads 1", "ros2_control"},
      {"none", "ros2_control"}};
  for (const auto& [method, kind] : runs) {
    const fs::path cfg = tmp / "cal.yaml", ctl = tmp / "ctl.txt";
    const auto r = run_cli("calibrate --track " + track_ + " --method " + method + " --config-out " +
                           cfg.string() + " --controller-out " + ctl.string() + " --controller " + kind);
    ASSERT_EQ(r.exit_code, 0) << method << ": " << r.err;
    EXPECT_THAT(r.out, HasSubstr("controller: " + ctl.string())) << method;
    const YAML::Node cal = YAML::LoadFile(cfg.string());
    const double rl = cal["wheel_radius_left_m"].as<double>(), rr = cal["wheel_radius_right_m"].as<double>(),
                 d = cal["wheel_base_m"].as<double>();
    const std::string text = slurp(ctl);
    EXPECT_THAT(text, HasSubstr("method " + method.substr(0, method.find(' ')))) << text;
    if (kind == "gazebo") {
      EXPECT_THAT(text, HasSubstr(fmt::format("<wheel_radius>{:.7f}</wheel_radius>", 0.5 * (rl + rr))));
      EXPECT_THAT(text, HasSubstr(fmt::format("<wheel_separation>{:.7f}</wheel_separation>", d)));
      continue;
    }
    std::map<std::string, double> p;
    if (kind == "ros1") {
      const YAML::Node c = YAML::LoadFile(ctl.string())["diff_drive_controller"];
      EXPECT_EQ(c["type"].as<std::string>(), "diff_drive_controller/DiffDriveController");
      for (const auto& kv : c)
        if (kv.first.as<std::string>() != "type") p[kv.first.as<std::string>()] = kv.second.as<double>();
    } else {
      p = ros2_params(ctl);
    }
    const Effective e = effective(p);
    EXPECT_NEAR(e.left_m, rl, 2e-7) << method;
    EXPECT_NEAR(e.right_m, rr, 2e-7) << method;
    EXPECT_NEAR(e.base_m, d, 4e-7) << method;
    if (kind.find("absolute") == std::string::npos) {
      EXPECT_DOUBLE_EQ(p.at("wheel_radius"), kRNom) << method;  // the track's nominal
      EXPECT_DOUBLE_EQ(p.at("wheel_separation"), kDNom) << method;
    } else {
      EXPECT_DOUBLE_EQ(p.at("wheel_separation_multiplier"), 1.0) << method;
    }
    if (method == "none") {
      for (const char* k :
           {"wheel_separation_multiplier", "left_wheel_radius_multiplier", "right_wheel_radius_multiplier"})
        EXPECT_DOUBLE_EQ(p.at(k), 1.0) << k;
    }
  }
}

TEST_F(CliController, NominalFlagsReplaceTheTrackMetadata) {
  TempDir tmp;
  const fs::path cfg = tmp / "cal.yaml", ctl = tmp / "ddc.yaml";
  const auto r = run_cli("calibrate --track " + track_ + " --method batch --config-out " + cfg.string() +
                         " --controller-out " + ctl.string() +
                         " --controller ros2_control --nominal-wheel-radius-m 0.33 --nominal-wheel-base-m 0.7");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto p = ros2_params(ctl);
  EXPECT_DOUBLE_EQ(p.at("wheel_radius"), 0.33);
  EXPECT_DOUBLE_EQ(p.at("wheel_separation"), 0.7);
  const YAML::Node cal = YAML::LoadFile(cfg.string());
  EXPECT_NEAR(p.at("left_wheel_radius_multiplier"), cal["wheel_radius_left_m"].as<double>() / 0.33, 5e-7);
  EXPECT_NEAR(p.at("wheel_separation_multiplier"), cal["wheel_base_m"].as<double>() / 0.7, 5e-7);
  EXPECT_THAT(slurp(ctl), HasSubstr("radius and wheel base given on the command line"));
}

// Each refusal: one line naming the flag, a non-zero exit, no file. The
// flags are checked before the tracks are read: with a missing track the
// error still names the flag.
TEST_F(CliController, InconsistentFlagsAreRefusedByNameBeforeAnyWork) {
  TempDir tmp;
  const std::string out = (tmp / "ddc.yaml").string(), json_out = (tmp / "c.json").string();
  const std::string missing = (tmp / "missing.csv").string();
  struct Case {
    std::string flags, flag, needle;  // the line starts with "odotune: FLAG" and holds NEEDLE
  };
  const std::string ctl = "--controller-out " + out;
  const std::vector<Case> cases = {
      {"--controller ros2_control", "--controller", "needs --controller-out FILE"},
      {ctl, "--controller-out", "needs --controller ros2_control, ros1 or gazebo"},
      {ctl + " --controller ros3", "--controller", "'ros3': expected ros2_control, ros1 or gazebo"},
      {"--controller-form absolute", "--controller-form", "needs --controller-out"},
      {"--controller-name ddc", "--controller-name", "needs --controller-out"},
      {"--nominal-wheel-radius-m 0.3", "--nominal-wheel-radius-m", "needs --controller-out"},
      {ctl + " --controller ros1 --controller-form relative", "--controller-form",
       "expected multipliers or absolute"},
      {ctl + " --controller gazebo --controller-form absolute", "--controller-form",
       "ros2_control and ros1 only"},
      {ctl + " --controller gazebo --controller-name ddc", "--controller-name", "ros2_control and ros1 only"},
      {ctl + " --controller ros1 --controller-name 'my ddc'", "--controller-name", "not a ROS name"},
      {ctl + " --controller ros1 --nominal-wheel-radius-m -0.3", "--nominal-wheel-radius-m",
       "finite length > 0"},
      {ctl + " --controller ros1 --nominal-wheel-base-m 0", "--nominal-wheel-base-m", "finite length > 0"},
      {"--controller-out " + (tmp / "no" / "dir.yaml").string() + " --controller ros1", "--controller-out",
       "does not exist"},
      {"--controller-out " + tmp.path().string() + " --controller ros1", "--controller-out", "is a folder"},
  };
  for (const Case& c : cases)
    for (const std::string& track : {track_, missing}) {
      const auto r = run_cli("calibrate --track " + track + " --method batch --json " + json_out + " " +
                             c.flags);
      EXPECT_NE(r.exit_code, 0) << c.flags;
      EXPECT_EQ(line_count(r.err), 1u) << r.err;
      EXPECT_THAT(r.err, StartsWith("odotune: " + c.flag + " ")) << r.err;
      EXPECT_THAT(r.err, HasSubstr(c.needle)) << r.err;
      EXPECT_EQ(tmp.entries(), 0u) << c.flags;
    }
  // --apply replays a calibration file: no controller file from it.
  const fs::path cfg = dir_->path() / "apply-cal.yaml";
  ASSERT_EQ(run_cli("calibrate --track " + track_ + " --method batch --config-out " + cfg.string()).exit_code,
            0);
  const auto r = run_cli("calibrate --apply " + cfg.string() + " --track " + track_ + " --controller-out " +
                         out + " --controller ros2_control");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--controller-out does not combine with --apply"));
  EXPECT_EQ(tmp.entries(), 0u);
}

// Flags that pass their checks, a calibration that fails afterwards: no
// controller file, no temporary left beside it.
TEST_F(CliController, AFailedRunWritesNoControllerFile) {
  TempDir tmp;
  const std::string no_ext = write_chair(tmp, "no_ext", 20.0, false);
  TempDir out_dir;
  const auto r = run_cli("calibrate --track " + no_ext + " --method dkf --controller-out " +
                         (out_dir / "ddc.yaml").string() + " --controller ros2_control");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--ext-from-gt"));
  EXPECT_EQ(out_dir.entries(), 0u);
}

// The round trip: calibrate (batch-pose), write the ros2_control file, read
// it back, apply its multipliers to the nominal geometry (effective =
// nominal × multiplier: what the controller will run with), state that as
// the track's nominal robot (robot.* metadata; the recording is the same)
// and calibrate again: nothing is left to correct.
//
// Tolerance: the second fit sees the same data and lands where the first did
// to within the fit's own precision (3 sd of its estimate, --json
// final_sd, relative: ~1e-6 with 1 mm ground-truth noise), plus the file's
// rounding, twice (the first file's multiplier and the second's, 6 decimals:
// 0.5e-6 each; the wheel_radius, 7 decimals on 0.32 m: 0.16e-6).
TEST_F(CliController, RoundTripThroughTheControllerFileLeavesNothingToCorrect) {
  TempDir tmp;
  const fs::path first = tmp / "first.yaml", first_json = tmp / "first.json";
  auto r = run_cli("calibrate --track " + track_ + " --method batch --json " + first_json.string() +
                   " --controller-out " + first.string() + " --controller ros2_control");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto p1 = ros2_params(first);
  const Effective e1 = effective(p1);
  // The fit found the misalignment (the calibration tests prove its accuracy).
  EXPECT_NEAR(p1.at("left_wheel_radius_multiplier"), kControllerScaleL, 2e-3);
  EXPECT_NEAR(p1.at("right_wheel_radius_multiplier"), kControllerScaleR, 2e-3);
  EXPECT_NEAR(p1.at("wheel_separation_multiplier"), kScaleD, 2e-3);
  const json j1 = json::parse(slurp(first_json));
  double rel_sd = 0.0;
  for (const char* k : {"wheel_radius_left_m", "wheel_radius_right_m", "wheel_base_m"})
    rel_sd = std::max(rel_sd, j1["final_sd"][k].get<double>() / j1["final"][k].get<double>());
  ASSERT_GT(rel_sd, 0.0);
  ASSERT_LT(rel_sd, 1e-4) << "a precise fit, or the round trip proves little";
  const double tol = 3.0 * rel_sd + 2 * 0.5e-6 + 0.16e-6;

  // The robot with the new parameters: the same recording, its nominal the applied geometry.
  tracks::TrackData data = tracks::read_track(track_).data();
  data.meta.wheel_radius_left_m = e1.left_m;
  data.meta.wheel_radius_right_m = e1.right_m;
  data.meta.wheel_base_m = e1.base_m;
  std::erase_if(data.meta.extra, [](const auto& kv) { return kv.first.rfind("sim.", 0) == 0; });
  const std::string applied = (tmp / "applied.csv").string();
  tracks::write_track(tracks::Track(std::move(data)), applied);

  const fs::path second = tmp / "second.yaml";
  r = run_cli("calibrate --track " + applied + " --method batch --controller-out " + second.string() +
              " --controller ros2_control");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto p2 = ros2_params(second);
  EXPECT_NEAR(p2.at("wheel_separation"), e1.base_m, 5e-8);
  EXPECT_NEAR(p2.at("wheel_separation_multiplier"), 1.0, tol);
  // The applied radii differ (R_L ≠ R_R) and a controller has one
  // wheel_radius: the file takes their mean, so its multipliers carry that
  // asymmetry; against each wheel's applied radius the change is 1.
  EXPECT_NEAR(p2.at("wheel_radius"), 0.5 * (e1.left_m + e1.right_m), 5e-8);
  const Effective e2 = effective(p2);
  EXPECT_NEAR(e2.left_m / e1.left_m, 1.0, tol);
  EXPECT_NEAR(e2.right_m / e1.right_m, 1.0, tol);
  EXPECT_THAT(slurp(second), HasSubstr("change against the nominal: left radius ×1.00000"));

  // With the configuration's own wheel_radius and wheel_separation as the
  // nominal, the second run gives back the first file: a fixed point.
  const fs::path kept = tmp / "kept.yaml";
  r = run_cli("calibrate --track " + applied + " --method batch --controller-out " + kept.string() +
              " --controller ros2_control --nominal-wheel-radius-m 0.32 --nominal-wheel-base-m 0.65");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto p3 = ros2_params(kept);
  for (const char* k :
       {"wheel_separation_multiplier", "left_wheel_radius_multiplier", "right_wheel_radius_multiplier"})
    EXPECT_NEAR(p3.at(k), p1.at(k), tol) << k;
}

// diagnose: the nominal robot × the fitted radius_error and wheel_base_error
// scales; a robot without them gets one line and no file.
TEST(CliControllerDiagnose, WritesTheCorrectedGeometryOrSaysThereIsNone) {
  TempDir tmp;
  const std::string scenario = std::string(ODOTUNE_SOURCE_DIR) + "/scenarios/track2.yaml";  // R 0.05 m, D 0.3 m
  const std::string bad = (tmp / "bad.csv").string(), ideal = (tmp / "ideal.csv").string();
  ASSERT_EQ(run_cli("simulate " + scenario + " -o " + bad + " --no-effects --effect " +
                    "radius_error:scale_l=0.99,scale_r=1.012 --effect wheel_base_error:scale=1.02")
                .exit_code,
            0);
  const fs::path ddc = tmp / "ddc.yaml", dj = tmp / "d.json";
  auto r = run_cli("diagnose " + bad + " --to 60 --json " + dj.string() + " --controller-out " + ddc.string() +
                   " --controller ros1 --controller-name base_controller");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("controller: " + ddc.string() + " (ros1 base_controller"));
  const YAML::Node c = YAML::LoadFile(ddc.string())["base_controller"];
  ASSERT_TRUE(c.IsMap()) << slurp(ddc);
  EXPECT_EQ(c["type"].as<std::string>(), "diff_drive_controller/DiffDriveController");
  EXPECT_DOUBLE_EQ(c["wheel_radius"].as<double>(), 0.05);
  EXPECT_DOUBLE_EQ(c["wheel_separation"].as<double>(), 0.3);
  std::map<std::string, double> fitted, stderrs;
  const json diagnosis = json::parse(slurp(dj));
  for (const json& f : diagnosis["findings"])
    for (const auto& [k, v] : f["params"].items()) {
      const std::string name = f["effect"].get<std::string>() + "." + k;
      fitted[name] = v.get<double>();
      stderrs[name] = f["stderr"][k].get<double>();
    }
  ASSERT_TRUE(fitted.count("radius_error.scale_l") && fitted.count("wheel_base_error.scale")) << slurp(dj);
  const std::vector<std::tuple<const char*, const char*, double>> checks = {
      {"left_wheel_radius_multiplier", "radius_error.scale_l", kControllerScaleL},
      {"right_wheel_radius_multiplier", "radius_error.scale_r", kControllerScaleR},
      {"wheel_separation_multiplier", "wheel_base_error.scale", kScaleD}};
  for (const auto& [key, param, truth] : checks) {
    const double m = c[key].as<double>();
    EXPECT_NEAR(m, fitted[param], 5e-7) << key;  // nominal × scale / nominal, 6 decimals
    EXPECT_NEAR(m, truth, std::max(5.0 * stderrs[param], 1e-4)) << key;
  }
  const std::string text = slurp(ddc);
  for (const char* line :
       {"# corrected by odotune diagnose", "# radius_error: scale_l = ", "# wheel_base_error: scale = ",
        "# held-out position error without → with radius_error",
        "# held-out position error, nominal → the whole chosen model"})
    EXPECT_THAT(text, HasSubstr(line));

  // Nothing to correct: one line, exit 0, no file.
  ASSERT_EQ(run_cli("simulate " + scenario + " -o " + ideal + " --no-effects").exit_code, 0);
  const fs::path none = tmp / "none.yaml";
  r = run_cli("diagnose " + ideal + " --to 60 --controller-out " + none.string() +
              " --controller ros2_control");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("controller: no radius_error or wheel_base_error found; " + none.string() +
                               " not written\n"));
  EXPECT_FALSE(fs::exists(none));

  // The flags are checked before the diagnosis, by name.
  r = run_cli("diagnose " + ideal + " --controller-out " + none.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--controller-out needs --controller"));
  EXPECT_FALSE(fs::exists(none));
}

}  // namespace
}  // namespace odotune::cli

// Scenario YAML (odotune/formats/scenario_yaml.h), the bundled reference scenarios and
// tracks, and the `odotune simulate` command end to end.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/formats/scenario_yaml.h>
#include <odotune/sim/effects.h>
#include <odotune/sim/simulator.h>
#include <odotune/tracks/track_io.h>

#include "support/cli_runner.h"

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::TempDir;

fs::path source_dir() { return fs::path(ODOTUNE_SOURCE_DIR); }
fs::path scenario_file(int i) { return source_dir() / "scenarios" / ("track" + std::to_string(i) + ".yaml"); }
fs::path track_file(int i) { return source_dir() / "data/tracks" / ("track" + std::to_string(i) + ".csv"); }

std::string first_difference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb;
  for (int line = 1;; ++line) {
    const bool ga = static_cast<bool>(std::getline(sa, la)), gb = static_cast<bool>(std::getline(sb, lb));
    if (!ga && !gb) return "identical";
    if (ga != gb || la != lb)
      return "line " + std::to_string(line) + ":\n  regenerated: " + (ga ? la : "<end>") +
             "\n  committed:   " + (gb ? lb : "<end>");
  }
}

// --- bundled reference tracks ----------------------------------------------

TEST(ReferenceScenarios, RegenerateTheCommittedTracksByteForByte) {
  for (int i = 1; i <= 5; ++i) {
    SCOPED_TRACE("track" + std::to_string(i));
    const sim::Scenario sc = formats::load_scenario(scenario_file(i));
    EXPECT_EQ(sc.source, "track" + std::to_string(i) + ".yaml");
    std::ostringstream out;
    tracks::format_track(sim::simulate(sc), out);
    const std::string committed = slurp(track_file(i));
    ASSERT_FALSE(committed.empty()) << "missing " << track_file(i);
    EXPECT_TRUE(out.str() == committed)
        << first_difference(out.str(), committed) << "\n(regenerate: see scenarios/README.md)";
  }
}

// Mean |heading rate| [rad/s] from the ground truth.
double mean_turn_rate(const tracks::Track& tr) {
  const auto& th = tr.col(tracks::Col::gt_theta);
  double sum = 0;
  for (std::size_t i = 1; i < tr.size(); ++i) sum += std::abs(th[i] - th[i - 1]);
  return sum / tr.duration_s();
}

TEST(ReferenceScenarios, TracksAreWellFormedAndTrack5TurnsMost) {
  std::vector<double> rate;
  for (int i = 1; i <= 5; ++i) {
    SCOPED_TRACE("track" + std::to_string(i));
    const tracks::Track tr = tracks::read_track(track_file(i));
    EXPECT_EQ(tr.meta().origin, "simulated");
    EXPECT_GE(tr.duration_s(), 120.0);
    EXPECT_LE(tr.duration_s(), 240.0);
    EXPECT_LT(fs::file_size(track_file(i)), 1'500'000u);
    EXPECT_TRUE(tr.has_ticks());
    for (tracks::Col c : {tracks::Col::gyro_z, tracks::Col::power_l, tracks::Col::power_r, tracks::Col::v_cmd,
                          tracks::Col::w_cmd, tracks::Col::v_ext, tracks::Col::w_ext, tracks::Col::v_ext_var,
                          tracks::Col::w_ext_var, tracks::Col::aps_x, tracks::Col::aps_y, tracks::Col::gt_x,
                          tracks::Col::gt_y, tracks::Col::gt_theta})
      EXPECT_TRUE(tr.has(c)) << tracks::column_name(c);
    EXPECT_EQ(tr.meta().get("sim.aps_rate_hz"), "1");
    EXPECT_EQ(tr.meta().get("sim.aps_sigma_m"), "0.06");
    EXPECT_NE(tr.meta().get("sim.effects"), "none");
    rate.push_back(mean_turn_rate(tr));
  }
  for (int i = 0; i < 4; ++i) EXPECT_GT(rate[4], 1.5 * rate[static_cast<std::size_t>(i)]) << "track" << i + 1;
}

// --- YAML errors -------------------------------------------------------------

std::string scenario_error_of(const std::string& yaml) {
  try {
    (void)formats::parse_scenario(yaml, "s.yaml");
  } catch (const formats::ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return e.what();
  }
  return "(accepted)";
}

const std::string kStraightMotion = "motion:\n  segments:\n    - straight: {distance_m: 1, speed_m_s: 0.5}\n";

TEST(ScenarioYaml, ParsesAFullScenario) {
  const sim::Scenario sc = formats::parse_scenario(R"(name: demo
seed: 17
robot: {wheel_base_m: 0.4, ticks_per_rev: 1000}
motion:
  max_accel_m_s2: 0.3
  segments:
    - stop: {duration_s: 1}
    - repeat:
        count: 3
        segments:
          - straight: {distance_m: -2, speed_m_s: 0.5}
          - arc: {radius_m: 1, angle_deg: -90, speed_m_s: 0.4}
    - spin: {angle_deg: 45, rate_deg_s: 30}
sensors:
  encoders: {rate_hz: 50, omega: true}
  aps: {sigma_m: 0.1}
  power: {enabled: false}
effects:
  radius_error: {scale_r: 1.01}
  time_offset: {dt: 0.02}
)",
                                                   "dir/demo.yaml");
  EXPECT_EQ(sc.name, "demo");
  EXPECT_EQ(sc.source, "demo.yaml");
  EXPECT_EQ(sc.seed, 17u);
  EXPECT_EQ(sc.robot.wheel_base_m, 0.4);
  EXPECT_EQ(sc.robot.wheel_radius_left_m, 0.05);  // default kept
  EXPECT_EQ(sc.motion.max_accel_m_s2, 0.3);
  ASSERT_EQ(sc.motion.segments.size(), 8u);
  EXPECT_EQ(sc.motion.segments[1].kind, sim::Segment::Kind::straight);
  EXPECT_EQ(sc.motion.segments[1].distance_m, -2.0);
  EXPECT_EQ(sc.motion.segments[1].line, 11);
  EXPECT_EQ(sc.motion.segments[6].kind, sim::Segment::Kind::arc);
  EXPECT_EQ(sc.motion.segments[7].rate_deg_s, 30.0);
  EXPECT_TRUE(sc.sensors.encoders.omega);
  EXPECT_EQ(sc.sensors.encoders.rate_hz, 50.0);
  EXPECT_EQ(sc.sensors.aps.sigma_m, 0.1);
  EXPECT_FALSE(sc.sensors.power.enabled);
  EXPECT_EQ(sim::format_effects(sc.effects), "radius_error:scale_l=1,scale_r=1.01; time_offset:dt=0.02");
}

TEST(ScenarioYaml, UnknownKeysSuggestTheClosest) {
  EXPECT_THAT(scenario_error_of("motion:\n  max_acel_m_s2: 0.5\n  segments: []\n"),
              AllOf(StartsWith("s.yaml:2: unknown key 'max_acel_m_s2' in motion"),
                    HasSubstr("did you mean 'max_accel_m_s2'")));
  EXPECT_THAT(scenario_error_of(kStraightMotion + "sensor:\n  aps: {rate_hz: 1}\n"),
              AllOf(StartsWith("s.yaml:4: unknown key 'sensor'"), HasSubstr("did you mean 'sensors'")));
  EXPECT_THAT(scenario_error_of("motion:\n  segments:\n    - straight: {distance_m: 1, sped_m_s: 0.5}\n"),
              AllOf(StartsWith("s.yaml:3:"), HasSubstr("'sped_m_s'"), HasSubstr("did you mean 'speed_m_s'")));
  EXPECT_THAT(scenario_error_of("motion:\n  segments:\n    - turn: {angle_deg: 90}\n"),
              AllOf(StartsWith("s.yaml:3:"), HasSubstr("unknown key 'turn'"),
                    HasSubstr("straight, arc, spin")));
  EXPECT_THAT(scenario_error_of(kStraightMotion + "sensors:\n  gyro: {sigma: 0.1}\n"),
              AllOf(StartsWith("s.yaml:5:"), HasSubstr("sensors.gyro"), HasSubstr("sigma_rad_s")));
}

TEST(ScenarioYaml, BadValuesNameKeyValueAndLine) {
  EXPECT_THAT(scenario_error_of("seed: abc\n" + kStraightMotion),
              AllOf(StartsWith("s.yaml:1: seed"), HasSubstr("non-negative integer"), HasSubstr("'abc'")));
  EXPECT_THAT(scenario_error_of("seed: -3\n" + kStraightMotion), StartsWith("s.yaml:1: seed"));
  EXPECT_THAT(scenario_error_of("robot:\n  wheel_base_m: fast\n" + kStraightMotion),
              AllOf(StartsWith("s.yaml:2: robot.wheel_base_m"), HasSubstr("'fast'")));
  EXPECT_THAT(scenario_error_of("robot:\n  wheel_base_m: -0.3\n" + kStraightMotion),
              AllOf(StartsWith("s.yaml:2: robot.wheel_base_m = -0.3"), HasSubstr("> 0")));
  EXPECT_THAT(scenario_error_of(kStraightMotion + "sensors:\n  gyro:\n    rate_hz: 300\n"),
              AllOf(StartsWith("s.yaml:6: sensors.gyro.rate_hz = 300"), HasSubstr("divides 1000 Hz")));
  EXPECT_THAT(scenario_error_of(kStraightMotion + "sensors:\n  aps: {enabled: maybe}\n"),
              AllOf(StartsWith("s.yaml:5:"), HasSubstr("true or false")));
  EXPECT_THAT(
      scenario_error_of(
          "motion:\n  segments:\n    - stop: {duration_s: 1}\n    - arc: {radius_m: -1, angle_deg: 90, speed_m_s: 0.3}\n"),
      AllOf(StartsWith("s.yaml:4:"), HasSubstr("radius_m = -1"), HasSubstr("expected a number > 0")));
  EXPECT_THAT(scenario_error_of("motion:\n  segments:\n    - straight: {distance_m: 1}\n"),
              AllOf(StartsWith("s.yaml:3:"), HasSubstr("missing 'speed_m_s'")));
  EXPECT_THAT(scenario_error_of("motion:\n  segments:\n    - repeat: {count: 0, segments: []}\n"),
              AllOf(StartsWith("s.yaml:3:"), HasSubstr("count = 0")));
  EXPECT_THAT(
      scenario_error_of(
          "motion:\n  max_accel_m_s2: 0\n  segments:\n    - straight: {distance_m: 1, speed_m_s: 0.5}\n"),
      AllOf(StartsWith("s.yaml:2:"), HasSubstr("max_accel_m_s2 = 0")));
}

TEST(ScenarioYaml, EffectErrorsUseTheVocabulary) {
  EXPECT_THAT(scenario_error_of(kStraightMotion + "effects:\n  lateral_skd: {k: 0.1}\n"),
              AllOf(StartsWith("s.yaml:5: unknown key 'lateral_skd' in effects"),
                    HasSubstr("did you mean 'lateral_skid'"), HasSubstr("radius_error")));
  EXPECT_THAT(
      scenario_error_of(kStraightMotion + "effects:\n  radius_error:\n    scale_l: 0.99\n    scale_r: 3\n"),
      AllOf(StartsWith("s.yaml:7: radius_error.scale_r = 3"), HasSubstr("out of range [0.5, 1.5]")));
  EXPECT_THAT(scenario_error_of(kStraightMotion + "effects:\n  radius_error: {scale: 1.01}\n"),
              AllOf(StartsWith("s.yaml:5:"), HasSubstr("'scale'"), HasSubstr("scale_l, scale_r")));
  EXPECT_THAT(scenario_error_of(kStraightMotion + "effects:\n  gyro_bias: {}\n"),
              AllOf(StartsWith("s.yaml:5:"), HasSubstr("needs parameter b")));
  EXPECT_THAT(scenario_error_of(kStraightMotion + "effects:\n  slip_zone: {x0: 1, x1: 0, y0: 0, y1: 1}\n"),
              AllOf(StartsWith("s.yaml:5:"), HasSubstr("x0 < x1")));
}

TEST(ScenarioYaml, ReadsOdometryBiasThroughTheEffectTable) {
  // physics-effects.md's 12th effect; b_v, b_w are optional (0 = no offset).
  const sim::Scenario sc = formats::parse_scenario(
      kStraightMotion + "effects:\n  odometry_bias: {b_w: -0.002}\n  gyro_bias: {b: 0.001}\n", "s.yaml");
  ASSERT_TRUE(sc.effects.odometry_bias);
  EXPECT_EQ(sc.effects.odometry_bias->b_v, 0.0);
  EXPECT_EQ(sc.effects.odometry_bias->b_w, -0.002);
  EXPECT_EQ(sim::format_effects(sc.effects), "gyro_bias:b=0.001; odometry_bias:b_v=0,b_w=-0.002");
  EXPECT_THAT(scenario_error_of(kStraightMotion + "effects:\n  odometry_bias:\n    b_v: 0.7\n"),
              AllOf(StartsWith("s.yaml:6: odometry_bias.b_v = 0.7"),
                    HasSubstr("out of range [-0.5, 0.5] m/s")));
  EXPECT_THAT(scenario_error_of(kStraightMotion + "effects:\n  odometry_bias: {bw: 0.1}\n"),
              AllOf(StartsWith("s.yaml:5:"), HasSubstr("'bw'"), HasSubstr("b_v, b_w")));
}

TEST(ScenarioYaml, StructuralErrors) {
  EXPECT_THAT(scenario_error_of("motion:\n  segments: [\n"),
              AllOf(StartsWith("s.yaml:"), HasSubstr("YAML syntax error")));
  EXPECT_THAT(scenario_error_of(""), HasSubstr("expected a scenario"));
  EXPECT_THAT(scenario_error_of("- 1\n- 2\n"), StartsWith("s.yaml:1: expected a scenario"));
  EXPECT_THAT(scenario_error_of("seed: 1\n"), HasSubstr("missing 'motion'"));
  EXPECT_THAT(scenario_error_of("motion:\n  segments: []\n"), HasSubstr("no segments"));
  EXPECT_THAT(scenario_error_of("seed: 1\nseed: 2\n" + kStraightMotion),
              AllOf(StartsWith("s.yaml:2:"), HasSubstr("duplicate key 'seed'")));
  EXPECT_THAT(
      scenario_error_of(
          "motion:\n  segments:\n    - {straight: {distance_m: 1, speed_m_s: 1}, stop: {duration_s: 1}}\n"),
      AllOf(StartsWith("s.yaml:3:"), HasSubstr("one-key map")));
}

TEST(ScenarioYaml, MissingFileIsOneLine) {
  try {
    (void)formats::load_scenario("/nonexistent/x.yaml");
    FAIL();
  } catch (const formats::ScenarioError& e) {
    EXPECT_THAT(e.what(), AllOf(StartsWith("/nonexistent/x.yaml: "), HasSubstr("no such file")));
  }
}

// --- the command ---------------------------------------------------------------

TEST(SimulateCommand, WritesATrackWithCommandLineEffects) {
  TempDir dir;
  const std::string out = (dir / "t.csv").string();
  const auto r = run_cli("simulate " + scenario_file(1).string() + " -o " + out +
                         " --seed 9 --no-effects --effect lateral_skid:k=0.05"
                         " --effect radius_error:scale_r=1.01 --effect radius_error:scale_l=0.99");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("wrote"));
  const tracks::Track tr = tracks::read_track(out);
  EXPECT_EQ(tr.meta().get("sim.seed"), "9");
  EXPECT_EQ(tr.meta().get("sim.scenario"), "track1.yaml");
  EXPECT_EQ(tr.meta().get("sim.effects"), "radius_error:scale_l=0.99,scale_r=1.01; lateral_skid:k=0.05");
  // Command-line effects add to the file's ones.
  const auto r2 = run_cli("simulate " + scenario_file(1).string() + " -o " + out +
                          " --effect time_offset:dt=0.01");
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_EQ(
      tracks::read_track(out).meta().get("sim.effects"),
      "radius_error:scale_l=0.997,scale_r=1.003; lateral_skid:k=0.02; gyro_bias:b=0.0015; time_offset:dt=0.01");
}

TEST(SimulateCommand, BadInputIsOneLineAndWritesNothing) {
  TempDir dir;
  const std::string out = (dir / "t.csv").string();
  const std::string sc = scenario_file(1).string();
  const auto one_line = [](const std::string& err) { return !err.empty() && err.find('\n') == err.size() - 1; };
  auto r = run_cli("simulate " + sc + " -o " + out + " --effect lateral_skd:k=0.1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(one_line(r.err)) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("lateral_skd"), HasSubstr("did you mean 'lateral_skid'")));
  r = run_cli("simulate " + sc + " -o " + out + " --effect radius_error:scale_l=9");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("radius_error.scale_l = 9"));
  r = run_cli("simulate " + sc + " -o " + out + " --seed -1");
  EXPECT_NE(r.exit_code, 0);
  const std::string bad = (dir / "bad.yaml").string();
  {
    std::ofstream f(bad);
    f << "seed: 1\nmotion:\n  segments:\n    - spin: {angle_deg: 90, rate_deg: 30}\n";
  }
  r = run_cli("simulate " + bad + " -o " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(one_line(r.err)) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr(bad + ":4:"), HasSubstr("did you mean 'rate_deg_s'")));
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);  // only bad.yaml
}

TEST(SimulateCommand, ListsTheEffects) {
  const auto r = run_cli("simulate --list-effects");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const auto& e : sim::effect_table()) EXPECT_THAT(r.out, HasSubstr(std::string(e.name)));
}

}  // namespace
}  // namespace odotune::cli

// The slip_episodes list of the scenario YAML (odotune/formats/scenario_yaml.h):
// parsing, FILE:LINE one-line errors, the write -> read round trip, and the
// wheelchair learning/slip scenarios (parse and validate; only the short
// round-trip scenario is simulated).
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/formats/scenario_yaml.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/random_slip.h>
#include <odotune/sim/simulator.h>
#include <odotune/sim/slip_episodes.h>
#include <odotune/tracks/track_io.h>

#include "support/cli_runner.h"

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;
using Kind = sim::SlipEpisode::Kind;
using Wheel = sim::SlipEpisode::Wheel;

// Lines 1-3; the motion lasts about 14 s.
const std::string kMotion = "motion:\n"
                            "  segments:\n"
                            "    - straight: {distance_m: 10, speed_m_s: 0.8}\n";

std::string error_of(const std::string& yaml) {
  try {
    (void)formats::parse_scenario(yaml, "s.yaml");
  } catch (const formats::ScenarioError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ScenarioSlipYaml, ParsesAListOfEpisodes) {
  const sim::Scenario sc = formats::parse_scenario(
      kMotion + "slip_episodes:\n"                                           // 4
                "  - {kind: spin, wheel: left, t0_s: 2, t1_s: 4, s: 0.6}\n"  // 5
                "  - kind: hold\n"                                           // 6
                "    wheel: right\n"
                "    t0_s: 3.5\n"
                "    t1_s: 7\n"
                "    s: 0.45\n"
                "    ramp_s: 0.5\n"
                "    brake_nm: 12.5\n",
      "s.yaml");
  ASSERT_EQ(sc.slip_episodes.size(), 2u);
  const sim::SlipEpisode& a = sc.slip_episodes[0];
  EXPECT_EQ(a.kind, Kind::spin);
  EXPECT_EQ(a.wheel, Wheel::left);
  EXPECT_EQ(a.t0_s, 2.0);
  EXPECT_EQ(a.t1_s, 4.0);
  EXPECT_EQ(a.s, 0.6);
  EXPECT_EQ(a.ramp_s, 0.2);    // default
  EXPECT_EQ(a.brake_nm, 0.0);  // default
  EXPECT_EQ(a.line, 5);
  const sim::SlipEpisode& b = sc.slip_episodes[1];
  EXPECT_EQ(b.kind, Kind::hold);
  EXPECT_EQ(b.wheel, Wheel::right);
  EXPECT_EQ(b.t0_s, 3.5);
  EXPECT_EQ(b.t1_s, 7.0);
  EXPECT_EQ(b.s, 0.45);
  EXPECT_EQ(b.ramp_s, 0.5);
  EXPECT_EQ(b.brake_nm, 12.5);
  EXPECT_EQ(b.line, 6);
  // An empty list or none at all.
  EXPECT_TRUE(formats::parse_scenario(kMotion + "slip_episodes: []\n", "s.yaml").slip_episodes.empty());
  EXPECT_TRUE(formats::parse_scenario(kMotion + "slip_episodes:\n", "s.yaml").slip_episodes.empty());
  EXPECT_TRUE(formats::parse_scenario(kMotion, "s.yaml").slip_episodes.empty());
}

TEST(ScenarioSlipYaml, ErrorsNameFileLineAndField) {
  const std::string list = kMotion + "slip_episodes:\n";  // items from line 5
  EXPECT_THAT(error_of(list + "  - {kind: spin, whel: left, t0_s: 2, t1_s: 4, s: 0.6}\n"),
              AllOf(StartsWith("s.yaml:5: unknown key 'whel' in slip_episodes[1]"),
                    HasSubstr("did you mean 'wheel'"),
                    HasSubstr("kind, wheel, t0_s, t1_s, s, ramp_s, brake_nm")));
  EXPECT_THAT(error_of(list + "  - {kind: spn, wheel: left, t0_s: 2, t1_s: 4, s: 0.6}\n"),
              AllOf(StartsWith("s.yaml:5: slip_episodes[1].kind = 'spn'"), HasSubstr("did you mean 'spin'"),
                    HasSubstr("expected spin or hold")));
  EXPECT_THAT(error_of(list + "  - {kind: spin, wheel: middle, t0_s: 2, t1_s: 4, s: 0.6}\n"),
              AllOf(StartsWith("s.yaml:5: slip_episodes[1].wheel = 'middle'"), HasSubstr("left or right")));
  EXPECT_THAT(error_of(list + "  - {kind: spin, wheel: left, t0_s: 2, t1_s: 4, s: 0.6}\n"
                              "  - kind: hold\n"
                              "    wheel: right\n"
                              "    t0_s: 2\n"
                              "    t1_s: 4\n"
                              "    s: 1.2\n"),  // line 10
              StartsWith("s.yaml:10: slip_episodes[2].s = 1.2; expected a strength in (0, 0.9]"));
  EXPECT_THAT(error_of(list + "  - kind: hold\n"
                              "    wheel: right\n"
                              "    t0_s: 2\n"
                              "    t1_s: 2.3\n"
                              "    s: 0.5\n"
                              "    ramp_s: 0.2\n"),  // line 10
              AllOf(StartsWith("s.yaml:10: slip_episodes[1].ramp_s = 0.2"),
                    HasSubstr("2*ramp_s <= t1_s - t0_s")));
  EXPECT_THAT(error_of(list + "  - kind: spin\n"
                              "    wheel: right\n"
                              "    t0_s: 2\n"
                              "    t1_s: 4\n"
                              "    s: 0.5\n"
                              "    brake_nm: 5\n"),  // line 10
              AllOf(StartsWith("s.yaml:10: slip_episodes[1].brake_nm = 5"), HasSubstr("hold episodes only")));
  EXPECT_THAT(error_of(list + "  - {kind: spin, wheel: left, t0_s: 2, s: 0.6}\n"),
              AllOf(StartsWith("s.yaml:5: slip_episodes[1]: missing 't1_s'"),
                    HasSubstr("kind, wheel, t0_s, t1_s and s")));
  EXPECT_THAT(error_of(list + "  - {kind: spin, wheel: left, t0_s: soon, t1_s: 4, s: 0.6}\n"),
              AllOf(StartsWith("s.yaml:5: slip_episodes[1].t0_s"), HasSubstr("finite number"),
                    HasSubstr("'soon'")));
  EXPECT_THAT(error_of(list + "  - {kind: spin, wheel: left, t0_s: 20, t1_s: 24, s: 0.6}\n"),
              AllOf(StartsWith("s.yaml:5: slip_episodes[1]: t0_s = 20"), HasSubstr("end of the motion")));
  EXPECT_THAT(error_of(list + "  - spin\n"),
              AllOf(StartsWith("s.yaml:5: slip_episodes[1]: expected a map"), HasSubstr("kind: spin")));
  EXPECT_THAT(error_of(kMotion + "slip_episodes: {kind: spin}\n"),
              AllOf(StartsWith("s.yaml:4: slip_episodes: expected a list"), HasSubstr("got a map")));
  EXPECT_THAT(error_of(kMotion + "slip_episode: []\n"),
              AllOf(StartsWith("s.yaml:4: unknown key 'slip_episode'"),
                    HasSubstr("did you mean 'slip_episodes'")));
  // Overlap on one wheel: at the later episode's line, naming both.
  EXPECT_THAT(error_of(list + "  - {kind: hold, wheel: left, t0_s: 2, t1_s: 6, s: 0.5, brake_nm: 9}\n"
                              "  - {kind: spin, wheel: right, t0_s: 3, t1_s: 5, s: 0.5}\n"
                              "  - {kind: spin, wheel: left, t0_s: 5, t1_s: 8, s: 0.5}\n"),  // line 7
              AllOf(StartsWith("s.yaml:7: slip_episodes[3] ([5, 8] s) overlaps slip_episodes[1] (line 5)"),
                    HasSubstr("left wheel")));
  for (const std::string& bad : {list + "  - {kind: spn, wheel: left, t0_s: 2, t1_s: 4, s: 0.6}\n",
                                 list + "  - {kind: spin, wheel: left, t0_s: 2, t1_s: 4, s: 0}\n"})
    EXPECT_THAT(error_of(bad), Not(HasSubstr("\n")));
}

TEST(ScenarioSlipYaml, WriteThenReadGivesTheSameEpisodesAndTrack) {
  sim::Scenario sc = formats::parse_scenario(kMotion, "s.yaml");
  sc.sensors.power.sigma_w = 0.5;
  sim::SlipEpisode a;
  a.kind = Kind::hold;
  a.wheel = Wheel::right;
  a.t0_s = 0.1 + 0.2;  // 0.30000000000000004: shortest round trip needed
  a.t1_s = 2.0 / 3.0 + 2;
  a.s = 0.55;
  a.ramp_s = 0.3;
  a.brake_nm = 0.1 * 3;
  sim::SlipEpisode b;
  b.kind = Kind::spin;
  b.wheel = Wheel::right;
  b.t0_s = 5;
  b.t1_s = 9.5;
  b.s = 0.9;
  sc.slip_episodes = {a, b};
  const std::string yaml = formats::scenario_to_yaml(sc, "slip round trip");
  EXPECT_THAT(yaml, HasSubstr("slip_episodes:\n  - {kind: hold, wheel: right, t0_s: 0.30000000000000004, "));
  EXPECT_THAT(yaml, HasSubstr("  - {kind: spin, wheel: right, t0_s: 5, t1_s: 9.5, s: 0.9, ramp_s: 0.2}\n"));
  const sim::Scenario back = formats::parse_scenario(yaml, "s.yaml");
  ASSERT_EQ(back.slip_episodes.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto &x = sc.slip_episodes[i], &y = back.slip_episodes[i];
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.wheel, y.wheel);
    EXPECT_EQ(x.t0_s, y.t0_s);
    EXPECT_EQ(x.t1_s, y.t1_s);
    EXPECT_EQ(x.s, y.s);
    EXPECT_EQ(x.ramp_s, y.ramp_s);
    EXPECT_EQ(x.brake_nm, y.brake_nm);
  }
  auto text = [](const sim::Scenario& s) {
    std::ostringstream out;
    tracks::format_track(sim::simulate(s), out);
    return out.str();
  };
  EXPECT_EQ(text(back), text(sc));
  // No episodes: no key written.
  sc.slip_episodes.clear();
  EXPECT_THAT(formats::scenario_to_yaml(sc, ""), Not(HasSubstr("slip_episodes")));
}

fs::path scenario(const std::string& stem) {
  return fs::path(ODOTUNE_SOURCE_DIR) / "scenarios" / (stem + ".yaml");
}

// The wheelchair robot and sensor set every learning/slip scenario shares
// (scenarios/README.md).
void expect_learning_setup(const sim::Scenario& sc) {
  SCOPED_TRACE(sc.name);
  std::string why;
  EXPECT_TRUE(sim::validate_scenario(sc, &why)) << why;
  EXPECT_EQ(sc.robot.wheel_radius_left_m, 0.32);
  EXPECT_EQ(sc.robot.wheel_radius_right_m, 0.32);
  EXPECT_EQ(sc.robot.wheel_base_m, 0.65);
  EXPECT_EQ(sc.robot.ticks_per_rev, 8800);
  const auto& s = sc.sensors;
  EXPECT_TRUE(s.power.enabled);
  EXPECT_EQ(s.power.rate_hz, 100);
  EXPECT_GT(s.power.sigma_w, 0.0);
  EXPECT_LE(s.power.sigma_w, 1.0);
  EXPECT_TRUE(s.encoders.enabled && s.gyro.enabled && s.ground_truth.enabled && s.ext_velocity.enabled);
  EXPECT_EQ(s.encoders.rate_hz, 100);
  EXPECT_EQ(s.gyro.rate_hz, 100);
  EXPECT_EQ(s.ground_truth.rate_hz, 100);
  EXPECT_EQ(s.ext_velocity.rate_hz, 10);
  EXPECT_FALSE(s.aps.enabled);
}

std::string route_of(const sim::Scenario& sc) {
  std::string r;
  for (const auto& g : sc.motion.segments)
    r += fmt::format("{}:{},{},{},{},{},{};", static_cast<int>(g.kind), g.distance_m, g.speed_m_s, g.radius_m,
                     g.angle_deg, g.rate_deg_s, g.duration_s);
  return r;
}

TEST(ScenarioSlipYaml, WheelchairLearningScenariosParseAndValidate) {
  const sim::Scenario learn = formats::load_scenario(scenario("wheelchair_learn"));
  const sim::Scenario eval = formats::load_scenario(scenario("wheelchair_learn_eval"));
  const sim::Scenario step = formats::load_scenario(scenario("wheelchair_learn_step"));
  for (const sim::Scenario* sc : {&learn, &eval, &step}) {
    expect_learning_setup(*sc);
    EXPECT_TRUE(sc->slip_episodes.empty());
    const auto& fx = sc->effects;
    EXPECT_TRUE(fx.radius_error && fx.wheel_base_error && fx.speed_radius && fx.longitudinal_slip) << sc->name;
  }
  EXPECT_NE(route_of(learn), route_of(eval));  // held out: a different drive
  EXPECT_EQ(route_of(step), route_of(eval));   // the eval drive with a radius step
  EXPECT_FALSE(learn.effects.radius_step || eval.effects.radius_step);
  ASSERT_TRUE(step.effects.radius_step);
  // Everything else as in the eval scenario.
  sim::Scenario same = step;
  same.effects.radius_step.reset();
  same.name = eval.name;
  EXPECT_EQ(formats::scenario_to_yaml(same, ""), formats::scenario_to_yaml(eval, ""));
  // The step at about 40 % of the drive.
  const double duration = sim::MotionProfile(step.motion).duration_s();
  EXPECT_GT(step.effects.radius_step->t, 0.3 * duration);
  EXPECT_LT(step.effects.radius_step->t, 0.5 * duration);
}

TEST(ScenarioSlipYaml, WheelchairSlipScenariosHaveEpisodesOfBothKindsOnBothWheels) {
  const sim::Scenario train = formats::load_scenario(scenario("wheelchair_slip"));
  const sim::Scenario eval = formats::load_scenario(scenario("wheelchair_slip_eval"));
  expect_learning_setup(train);
  expect_learning_setup(eval);
  EXPECT_NE(route_of(train), route_of(eval));
  EXPECT_GE(train.slip_episodes.size(), 8u);
  EXPECT_LE(train.slip_episodes.size(), 10u);
  EXPECT_GE(eval.slip_episodes.size(), 4u);
  EXPECT_LE(eval.slip_episodes.size(), 5u);
  for (const sim::Scenario* sc : {&train, &eval}) {
    for (const auto& e : sc->slip_episodes) {
      EXPECT_GE(e.t1_s - e.t0_s, 2.0) << sc->name;
      EXPECT_LE(e.t1_s - e.t0_s, 5.0) << sc->name;
      EXPECT_GE(e.s, 0.3) << sc->name;
      EXPECT_LE(e.s, 0.8) << sc->name;
      EXPECT_GT(e.line, 0);
    }
  }
  std::set<std::pair<int, int>> train_kinds;
  for (const auto& e : train.slip_episodes)
    train_kinds.insert({static_cast<int>(e.kind), static_cast<int>(e.wheel)});
  EXPECT_EQ(train_kinds.size(), 4u);  // spin and hold, each on both wheels
  std::set<int> eval_kinds, eval_wheels;
  for (const auto& e : eval.slip_episodes) {
    eval_kinds.insert(static_cast<int>(e.kind));
    eval_wheels.insert(static_cast<int>(e.wheel));
  }
  EXPECT_EQ(eval_kinds.size(), 2u);
  EXPECT_EQ(eval_wheels.size(), 2u);
}

TEST(ScenarioSlipYaml, SimulateRandomSlipWritesTheSeededLayoutInPlaceOfTheScenarios) {
  testing_support::TempDir dir("random-slip");
  const std::string file = scenario("wheelchair_slip_eval").string();
  const std::string out = (dir / "drive.csv").string();
  const auto r = testing_support::run_cli(fmt::format("simulate {} --random-slip 5 -o {}", file, out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("(random layout 5)"));
  const sim::Scenario sc = formats::load_scenario(file);
  const auto expected = sim::random_slip_episodes(sim::MotionProfile(sc.motion), 5);
  ASSERT_FALSE(expected.empty());
  const std::vector<sim::SlipEpisode> written = sim::slip_episodes_from_metadata(
      tracks::read_track(out).meta());
  EXPECT_EQ(sim::format_slip_episodes(written), sim::format_slip_episodes(expected));
  EXPECT_NE(sim::format_slip_episodes(written), sim::format_slip_episodes(sc.slip_episodes));

  const auto bad = testing_support::run_cli(fmt::format("simulate {} --random-slip -3 -o {}", file,
                                                        (dir / "bad.csv").string()));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_THAT(bad.err, HasSubstr("--random-slip -3: expected a non-negative integer"));
  EXPECT_FALSE(fs::exists(dir / "bad.csv"));
}

}  // namespace
}  // namespace odotune::cli

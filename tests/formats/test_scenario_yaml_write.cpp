// scenario_to_yaml (odotune/formats/scenario_yaml.h) and the motion.knots form of the
// scenario reader: a written scenario parses back to the same fields and
// simulates to a byte-identical track; knots errors name file and line.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/formats/scenario_yaml.h>
#include <odotune/sim/effects.h>
#include <odotune/sim/scenario_from_track.h>
#include <odotune/sim/simulator.h>
#include <odotune/tracks/track_io.h>

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

fs::path source_root() { return fs::path(ODOTUNE_SOURCE_DIR); }
fs::path bundled_scenario(int i) {
  return source_root() / "scenarios" / ("track" + std::to_string(i) + ".yaml");
}

std::string track_text(const sim::Scenario& sc) {
  std::ostringstream out;
  tracks::format_track(sim::simulate(sc), out);
  return out.str();
}

// Every field the reader reads (not `source`, which comes from the file name,
// nor Segment::line). Doubles compared exactly.
void expect_same(const sim::Scenario& a, const sim::Scenario& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.step_s, b.step_s);
  const auto &ra = a.robot, &rb = b.robot;
  EXPECT_EQ(ra.wheel_radius_left_m, rb.wheel_radius_left_m);
  EXPECT_EQ(ra.wheel_radius_right_m, rb.wheel_radius_right_m);
  EXPECT_EQ(ra.wheel_base_m, rb.wheel_base_m);
  EXPECT_EQ(ra.ticks_per_rev, rb.ticks_per_rev);
  EXPECT_EQ(ra.mass_kg, rb.mass_kg);
  EXPECT_EQ(ra.yaw_inertia_kg_m2, rb.yaw_inertia_kg_m2);
  EXPECT_EQ(ra.wheel_inertia_kg_m2, rb.wheel_inertia_kg_m2);
  EXPECT_EQ(ra.viscous_friction_nm_s, rb.viscous_friction_nm_s);
  EXPECT_EQ(ra.coulomb_friction_nm, rb.coulomb_friction_nm);
  EXPECT_EQ(ra.coulomb_smoothing_rad_s, rb.coulomb_smoothing_rad_s);
  EXPECT_EQ(ra.torque_constant_nm_per_a, rb.torque_constant_nm_per_a);
  EXPECT_EQ(ra.coil_resistance_ohm, rb.coil_resistance_ohm);
  const auto &ma = a.motion, &mb = b.motion;
  EXPECT_EQ(ma.start_x_m, mb.start_x_m);
  EXPECT_EQ(ma.start_y_m, mb.start_y_m);
  EXPECT_EQ(ma.start_theta_rad, mb.start_theta_rad);
  EXPECT_EQ(ma.max_accel_m_s2, mb.max_accel_m_s2);
  EXPECT_EQ(ma.max_angular_accel_rad_s2, mb.max_angular_accel_rad_s2);
  ASSERT_EQ(ma.segments.size(), mb.segments.size());
  for (std::size_t i = 0; i < ma.segments.size(); ++i) {
    SCOPED_TRACE("segment " + std::to_string(i + 1));
    const auto &sa = ma.segments[i], &sb = mb.segments[i];
    EXPECT_EQ(sa.kind, sb.kind);
    EXPECT_EQ(sa.distance_m, sb.distance_m);
    EXPECT_EQ(sa.speed_m_s, sb.speed_m_s);
    EXPECT_EQ(sa.radius_m, sb.radius_m);
    EXPECT_EQ(sa.angle_deg, sb.angle_deg);
    EXPECT_EQ(sa.rate_deg_s, sb.rate_deg_s);
    EXPECT_EQ(sa.duration_s, sb.duration_s);
  }
  ASSERT_EQ(ma.knots.size(), mb.knots.size());
  for (std::size_t i = 0; i < ma.knots.size(); ++i) {
    SCOPED_TRACE("knot " + std::to_string(i + 1));
    EXPECT_EQ(ma.knots[i].t_s, mb.knots[i].t_s);
    EXPECT_EQ(ma.knots[i].v_m_s, mb.knots[i].v_m_s);
    EXPECT_EQ(ma.knots[i].w_rad_s, mb.knots[i].w_rad_s);
    EXPECT_EQ(std::signbit(ma.knots[i].v_m_s), std::signbit(mb.knots[i].v_m_s));
  }
  const auto &s = a.sensors, &t = b.sensors;
  EXPECT_EQ(s.encoders.enabled, t.encoders.enabled);
  EXPECT_EQ(s.encoders.rate_hz, t.encoders.rate_hz);
  EXPECT_EQ(s.encoders.omega, t.encoders.omega);
  EXPECT_EQ(s.encoders.omega_resolution_rad_s, t.encoders.omega_resolution_rad_s);
  EXPECT_EQ(s.commands.enabled, t.commands.enabled);
  EXPECT_EQ(s.commands.rate_hz, t.commands.rate_hz);
  EXPECT_EQ(s.commands.resolution, t.commands.resolution);
  EXPECT_EQ(s.gyro.enabled, t.gyro.enabled);
  EXPECT_EQ(s.gyro.rate_hz, t.gyro.rate_hz);
  EXPECT_EQ(s.gyro.sigma_rad_s, t.gyro.sigma_rad_s);
  EXPECT_EQ(s.gyro.resolution_rad_s, t.gyro.resolution_rad_s);
  EXPECT_EQ(s.power.enabled, t.power.enabled);
  EXPECT_EQ(s.power.rate_hz, t.power.rate_hz);
  EXPECT_EQ(s.power.sigma_w, t.power.sigma_w);
  EXPECT_EQ(s.power.resolution_w, t.power.resolution_w);
  EXPECT_EQ(s.ext_velocity.enabled, t.ext_velocity.enabled);
  EXPECT_EQ(s.ext_velocity.rate_hz, t.ext_velocity.rate_hz);
  EXPECT_EQ(s.ext_velocity.sigma_v_m_s, t.ext_velocity.sigma_v_m_s);
  EXPECT_EQ(s.ext_velocity.sigma_w_rad_s, t.ext_velocity.sigma_w_rad_s);
  EXPECT_EQ(s.ext_velocity.resolution, t.ext_velocity.resolution);
  EXPECT_EQ(s.aps.enabled, t.aps.enabled);
  EXPECT_EQ(s.aps.rate_hz, t.aps.rate_hz);
  EXPECT_EQ(s.aps.sigma_m, t.aps.sigma_m);
  EXPECT_EQ(s.aps.resolution_m, t.aps.resolution_m);
  EXPECT_EQ(s.ground_truth.enabled, t.ground_truth.enabled);
  EXPECT_EQ(s.ground_truth.rate_hz, t.ground_truth.rate_hz);
  EXPECT_EQ(s.ground_truth.sigma_m, t.ground_truth.sigma_m);
  EXPECT_EQ(s.ground_truth.sigma_rad, t.ground_truth.sigma_rad);
  EXPECT_EQ(s.ground_truth.resolution_m, t.ground_truth.resolution_m);
  EXPECT_EQ(s.ground_truth.resolution_rad, t.ground_truth.resolution_rad);
  // Every parameter of every active effect, exactly (shortest round-trip
  // numbers: equal text <=> equal doubles).
  const auto ea = sim::active_effects(a.effects), eb = sim::active_effects(b.effects);
  ASSERT_EQ(ea.size(), eb.size());
  for (std::size_t i = 0; i < ea.size(); ++i) {
    EXPECT_EQ(ea[i].name, eb[i].name);
    ASSERT_EQ(ea[i].values.size(), eb[i].values.size());
    for (std::size_t j = 0; j < ea[i].values.size(); ++j) {
      EXPECT_EQ(ea[i].values[j].first, eb[i].values[j].first);
      EXPECT_EQ(ea[i].values[j].second, eb[i].values[j].second) << ea[i].name << "." << ea[i].values[j].first;
    }
  }
}

TEST(ScenarioYamlWrite, ReferenceScenariosRoundTripAndSimulateIdentically) {
  for (int i = 1; i <= 5; ++i) {
    SCOPED_TRACE("track" + std::to_string(i));
    const sim::Scenario sc = formats::load_scenario(bundled_scenario(i));
    const std::string yaml = formats::scenario_to_yaml(sc, "written back by the test\nsecond line");
    EXPECT_THAT(yaml, StartsWith("# written back by the test\n# second line\n\nname: \"track"));
    EXPECT_THAT(yaml, Not(HasSubstr("start")));  // at the origin: written as before the start pose existed
    const sim::Scenario back = formats::parse_scenario(yaml, sc.source);
    expect_same(sc, back);
    EXPECT_EQ(back.source, sc.source);
    EXPECT_TRUE(track_text(back) == track_text(sc)) << "re-simulated track differs";
  }
}

// Awkward numbers, every effect, unusual sensors and a name that needs quoting.
sim::Scenario knots_scenario() {
  sim::Scenario sc;
  sc.name = "corrected \"run\": #1 \\ back\tslash \xc3\xbc";
  sc.source = "knots.yaml";  // what parse_scenario(.., "knots.yaml") sets
  sc.seed = 18446744073709551615ull;
  sc.step_s = 0.002;
  sc.robot.wheel_radius_left_m = 0.1 + 0.2;  // 0.30000000000000004
  sc.robot.wheel_base_m = 1.0 / 3.0;
  sc.robot.ticks_per_rev = 1e6;
  sc.robot.mass_kg = 1e-7;
  sc.motion.max_accel_m_s2 = 123456.789e-3;
  sc.motion.start_x_m = 0.1 + 0.2;
  sc.motion.start_y_m = -1e-3;
  sc.motion.start_theta_rad = -2.0 / 3.0;
  sc.motion.knots = {{0, -0.0, 0},    {0.1, 0.1 + 0.2, 1.0 / 3.0}, {0.7, 0.45, -2.0 / 7.0}, {2.5, 0.5, 1e-300},
                     {4, -0.25, 0.1}, {5.000000000000001, 0, 0}};
  auto& s = sc.sensors;
  s.encoders.rate_hz = 50;
  s.encoders.omega = true;
  s.encoders.omega_resolution_rad_s = 0;
  s.commands.rate_hz = 250;
  s.gyro.rate_hz = 500.0;
  s.gyro.sigma_rad_s = 0.0031415926535897933;
  s.power.enabled = false;
  s.power.rate_hz = 7;  // not checked while disabled, must still round-trip
  s.ext_velocity.rate_hz = 10;
  s.aps.rate_hz = 2;
  s.aps.sigma_m = 0.05;
  s.ground_truth.rate_hz = 100;
  s.ground_truth.sigma_rad = 1e-3;
  for (const char* e : {"radius_error:scale_l=0.997,scale_r=1.0030000000000001", "wheel_base_error:scale=1.02",
                        "radius_step:t=2,scale_l=0.99", "speed_radius:c=-0.01", "lateral_skid:k=0.021",
                        "longitudinal_slip:k=0.05", "slip_zone:x0=-1,x1=0.5,y0=-0.25,y1=1e-3,s_l=0.3",
                        "gyro_bias:b=-0.0015", "gyro_scale:s=0.995", "actuator_lag:tau=0.05",
                        "time_offset:dt=-0.01", "odometry_bias:b_v=-0.0030000000000000001,b_w=1e-4"})
    sim::apply_effect(sc.effects, sim::parse_effect_spec(e));
  return sc;
}

TEST(ScenarioYamlWrite, KnotsScenarioWithAllEffectsRoundTripsExactly) {
  const sim::Scenario sc = knots_scenario();
  ASSERT_EQ(sim::active_effects(sc.effects).size(), sim::effect_table().size());
  const std::string yaml = formats::scenario_to_yaml(sc, "");
  EXPECT_THAT(yaml, StartsWith("name: "));  // no header
  EXPECT_THAT(yaml, HasSubstr("\n    - [0.1, 0.30000000000000004, 0.3333333333333333]\n"));
  EXPECT_THAT(yaml, HasSubstr("\n    - [0, -0, 0]\n"));
  EXPECT_THAT(yaml, HasSubstr("\nmotion:\n  start: {x_m: 0.30000000000000004, y_m: -0.001, "
                              "theta_rad: -0.6666666666666666}\n"));
  const sim::Scenario back = formats::parse_scenario(yaml, "knots.yaml");
  expect_same(sc, back);
  EXPECT_TRUE(track_text(back) == track_text(sc)) << "re-simulated track differs";
  // One non-zero coordinate is enough for all three to be written.
  sim::Scenario only_theta = sc;
  only_theta.motion.start_x_m = only_theta.motion.start_y_m = 0;
  const std::string yaml2 = formats::scenario_to_yaml(only_theta, "");
  EXPECT_THAT(yaml2, HasSubstr("\n  start: {x_m: 0, y_m: 0, theta_rad: -0.6666666666666666}\n"));
  expect_same(only_theta, formats::parse_scenario(yaml2, "knots.yaml"));
}

TEST(ScenarioYamlWrite, TheCorrectedScenarioOfATrackRoundTrips) {
  // The diagnose flow: track -> scenario_from_track -> YAML -> simulate.
  const tracks::Track tr = tracks::read_track(source_root() / "data/tracks/track2.csv");
  sim::Scenario sc = sim::scenario_from_track(tr, {"lateral_skid:k=0.021", "radius_error:scale_l=0.996"});
  sc.source = "track2-corrected.yaml";
  const std::string yaml = formats::scenario_to_yaml(
      sc, "odotune diagnose: corrected model of track2\n\neffects: ...");
  EXPECT_THAT(yaml, StartsWith("# odotune diagnose: corrected model of track2\n#\n# effects: ...\n\n"));
  const sim::Scenario back = formats::parse_scenario(yaml, "track2-corrected.yaml");
  expect_same(sc, back);
  EXPECT_TRUE(track_text(back) == track_text(sc)) << "re-simulated track differs";
  // Its start is the recording's first ground-truth pose (track2 starts at
  // the origin; the fit reproduces it to the columns' 1e-5 m / 1e-6 rad).
  EXPECT_NEAR(back.motion.start_x_m, tr.col(tracks::Col::gt_x).front(), 1e-4);
  EXPECT_NEAR(back.motion.start_y_m, tr.col(tracks::Col::gt_y).front(), 1e-4);
  EXPECT_NEAR(back.motion.start_theta_rad, tr.col(tracks::Col::gt_theta).front(), 1e-4);
}

TEST(ScenarioYamlWrite, RefusesWhatTheReaderWouldReject) {
  auto write_error_of = [](const sim::Scenario& sc) -> std::string {
    try {
      (void)formats::scenario_to_yaml(sc, "x");
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
      return e.what();
    }
    return "(accepted)";
  };
  const sim::Scenario good = knots_scenario();
  sim::Scenario sc = good;
  sc.name = "";
  EXPECT_THAT(write_error_of(sc), HasSubstr("name"));
  sc.name = "two\nlines";
  EXPECT_THAT(write_error_of(sc), HasSubstr("one-line"));
  sc = good;
  sc.motion.knots.clear();
  EXPECT_THAT(write_error_of(sc), HasSubstr("neither segments nor knots"));
  sc = good;
  sc.motion.segments.resize(1);
  EXPECT_THAT(write_error_of(sc), HasSubstr("segments and knots both given"));
  sc = good;
  sc.sensors.power.rate_hz = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(write_error_of(sc), HasSubstr("sensors.power.rate_hz = nan"));
  sc = good;
  sc.robot.wheel_base_m = -1;
  EXPECT_THAT(write_error_of(sc), HasSubstr("robot.wheel_base_m = -1"));
}

// --- motion.knots in the reader ------------------------------------------------------

std::string write_error_of(const std::string& yaml) {
  try {
    (void)formats::parse_scenario(yaml, "s.yaml");
  } catch (const formats::ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return e.what();
  }
  return "(accepted)";
}

TEST(ScenarioYamlKnots, ParsesTriples) {
  const sim::Scenario sc = formats::parse_scenario(
      "motion:\n  max_accel_m_s2: 0.3\n  knots:\n    - [0, 0, 0]\n    - [1.5, 0.5, -0.25]\n"
      "    - [2, +0, 1e-3]\n",
      "k.yaml");
  EXPECT_TRUE(sc.motion.segments.empty());
  ASSERT_EQ(sc.motion.knots.size(), 3u);
  EXPECT_EQ(sc.motion.knots[1].t_s, 1.5);
  EXPECT_EQ(sc.motion.knots[1].v_m_s, 0.5);
  EXPECT_EQ(sc.motion.knots[1].w_rad_s, -0.25);
  EXPECT_EQ(sc.motion.knots[2].w_rad_s, 1e-3);
  EXPECT_EQ(sc.motion.max_accel_m_s2, 0.3);
}

TEST(ScenarioYamlKnots, ErrorsNameFileLineAndKnot) {
  const std::string seg = "motion:\n  segments:\n    - stop: {duration_s: 1}\n";
  EXPECT_THAT(write_error_of(seg + "  knots:\n    - [0, 0, 0]\n"),
              AllOf(StartsWith("s.yaml:4: motion: segments and knots both given"), HasSubstr("expected one")));
  EXPECT_THAT(write_error_of("motion:\n  knots:\n    - [0, 0]\n"),
              AllOf(StartsWith("s.yaml:3: motion.knots[1]: expected a list [t_s, v_m_s, w_rad_s] of 3 numbers"),
                    HasSubstr("got 2 items")));
  EXPECT_THAT(write_error_of("motion:\n  knots:\n    - [0, 0, 0]\n    - {t: 1}\n"),
              StartsWith("s.yaml:4: motion.knots[2]: expected a list [t_s, v_m_s, w_rad_s]"));
  EXPECT_THAT(write_error_of("motion:\n  knots:\n    - [0, fast, 0]\n"),
              AllOf(StartsWith("s.yaml:3: motion.knots[1].v_m_s"), HasSubstr("'fast'")));
  EXPECT_THAT(write_error_of("motion:\n  knots:\n    - [0, 0, 0]\n    - [1, 0.2, 0]\n    - [0.5, 0.2, 0]\n"),
              AllOf(StartsWith("s.yaml:5: motion: knot 3: t_s = 0.5"), HasSubstr("strictly increasing")));
  EXPECT_THAT(write_error_of("motion:\n  knots:\n    - [1, 0, 0]\n"),
              AllOf(StartsWith("s.yaml:3: motion: knot 1: t_s = 1"), HasSubstr("0 for the first knot")));
  EXPECT_THAT(write_error_of("motion:\n  knots: []\n"), AllOf(StartsWith("s.yaml:2: motion.knots: no knots")));
  EXPECT_THAT(write_error_of("motion:\n  knots: {t_s: [0]}\n"),
              AllOf(StartsWith("s.yaml:2:"), HasSubstr("expected a list of [t_s, v_m_s, w_rad_s] triples")));
  EXPECT_THAT(write_error_of("motion:\n  max_accel_m_s2: 1\n"),
              AllOf(StartsWith("s.yaml:2:"), HasSubstr("no segments or knots")));
  EXPECT_THAT(write_error_of("motion:\n  knot: []\n"), HasSubstr("did you mean 'knots'"));
}

// --- motion.start in the reader ------------------------------------------------------

TEST(ScenarioYamlStart, ParsesTheStartPoseEachKeyOptional) {
  const std::string seg = "  segments:\n    - stop: {duration_s: 1}\n";
  sim::Scenario sc = formats::parse_scenario("motion:\n  start: {x_m: 1.5, y_m: -2, theta_rad: 0.7}\n" + seg,
                                             "a.yaml");
  EXPECT_EQ(sc.motion.start_x_m, 1.5);
  EXPECT_EQ(sc.motion.start_y_m, -2.0);
  EXPECT_EQ(sc.motion.start_theta_rad, 0.7);
  sc = formats::parse_scenario("motion:\n  start:\n    theta_rad: -3\n" + seg, "a.yaml");
  EXPECT_EQ(sc.motion.start_x_m, 0.0);
  EXPECT_EQ(sc.motion.start_y_m, 0.0);
  EXPECT_EQ(sc.motion.start_theta_rad, -3.0);
  sc = formats::parse_scenario("motion:\n  start: {}\n" + seg, "a.yaml");
  EXPECT_EQ(sc.motion.start_x_m, 0.0);
  sc = formats::parse_scenario("motion:\n" + seg, "a.yaml");
  EXPECT_EQ(sc.motion.start_theta_rad, 0.0);
  // ... and the simulated ground truth starts there.
  sc = formats::parse_scenario("motion:\n  start: {x_m: 1.5, y_m: -2, theta_rad: 0.7}\n" + seg, "a.yaml");
  const tracks::Track tr = sim::simulate(sc);
  EXPECT_EQ(tr.col(tracks::Col::gt_x).front(), 1.5);
  EXPECT_EQ(tr.col(tracks::Col::gt_y).front(), -2.0);
  EXPECT_EQ(tr.col(tracks::Col::gt_theta).front(), 0.7);
}

TEST(ScenarioYamlStart, ErrorsNameFileLineAndKey) {
  const std::string seg = "  segments:\n    - stop: {duration_s: 1}\n";
  EXPECT_THAT(write_error_of("motion:\n" + seg + "  start:\n    x_m: .nan\n"),
              AllOf(StartsWith("s.yaml:5: motion.start.x_m: expected a finite number"), HasSubstr("'.nan'")));
  EXPECT_THAT(write_error_of("motion:\n  start: {y_m: 1e999}\n" + seg),
              StartsWith("s.yaml:2: motion.start.y_m: expected a finite number, got '1e999'"));
  EXPECT_THAT(write_error_of("motion:\n  start: {theta_rad: north}\n" + seg),
              StartsWith("s.yaml:2: motion.start.theta_rad: expected a finite number, got 'north'"));
  EXPECT_THAT(write_error_of("motion:\n  start: {x: 1}\n" + seg),
              AllOf(StartsWith("s.yaml:2: unknown key 'x' in motion.start"),
                    HasSubstr("valid keys: x_m, y_m, theta_rad")));
  EXPECT_THAT(write_error_of("motion:\n  start: {theta_deg: 90}\n" + seg),
              HasSubstr("did you mean 'theta_rad'"));
  EXPECT_THAT(write_error_of("motion:\n  start: [1, 2, 0]\n" + seg),
              AllOf(StartsWith("s.yaml:2: motion.start: expected a map"), HasSubstr("got a list")));
  EXPECT_THAT(write_error_of("motion:\n  start: {x_m: 1, x_m: 2}\n" + seg),
              HasSubstr("duplicate key 'motion.start.x_m'"));
  EXPECT_THAT(write_error_of("motion:\n  starts: {x_m: 1}\n" + seg), HasSubstr("did you mean 'start'"));
}

}  // namespace
}  // namespace odotune::cli

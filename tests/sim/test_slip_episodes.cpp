// Slip episodes (SlipEpisode in scenario.h, slip_episodes.h; physics in
// simulator.h "Slip episodes"): a spin keeps the ticks but lowers the wheel's
// power and shortens the true travel; a hold lowers the ticks, raises the
// power and leaves the true path alone; outside episodes nothing changes; the
// ramps; the metadata text round trip and its errors; validation; seeding.
//
// Expected numbers come from the model's equations in simulator.h evaluated
// here by hand (steady cruise: body accelerations 0), never from the
// simulator's own output.
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/sim/simulator.h>
#include <odotune/sim/slip_episodes.h>
#include <odotune/tracks/track_io.h>

namespace odotune::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;
using Kind = SlipEpisode::Kind;
using Wheel = SlipEpisode::Wheel;

// The chair's cruise in the scenarios below: 0.8 m/s on 0.32 m wheels.
constexpr double kSpeed = 0.8, kRadius = 0.32, kOmega = kSpeed / kRadius;  // [m/s, m, rad/s]

// The wheelchair of scenarios/wheelchair.yaml (power model included), a
// straight at kSpeed with a long cruise (t ~ 2.6 .. 13.5 s), all sensors at
// 100 Hz without noise and at full precision.
Scenario chair() {
  Scenario sc;
  sc.seed = 7;
  RobotParams& r = sc.robot;
  r.wheel_radius_left_m = r.wheel_radius_right_m = kRadius;
  r.wheel_base_m = 0.65;
  r.ticks_per_rev = 8800;
  r.mass_kg = 130;
  r.yaw_inertia_kg_m2 = 18;
  r.wheel_inertia_kg_m2 = 0.4;
  r.viscous_friction_nm_s = 0.5;
  r.coulomb_friction_nm = 3;
  r.coulomb_smoothing_rad_s = 0.2;
  r.torque_constant_nm_per_a = 8;
  r.coil_resistance_ohm = 0.3;
  Segment rest;
  rest.kind = Segment::Kind::stop;
  rest.duration_s = 1;
  Segment go;
  go.kind = Segment::Kind::straight;
  go.distance_m = 10;
  go.speed_m_s = kSpeed;
  sc.motion.max_accel_m_s2 = 0.5;
  sc.motion.segments = {rest, go, rest};
  auto& s = sc.sensors;
  s.encoders.omega = true;
  s.encoders.omega_resolution_rad_s = 0;
  s.commands.resolution = 0;
  s.gyro.sigma_rad_s = 0;
  s.gyro.resolution_rad_s = 0;
  s.power.sigma_w = 0;
  s.power.resolution_w = 0;
  s.ext_velocity.rate_hz = 100;
  s.ext_velocity.sigma_v_m_s = 0;
  s.ext_velocity.sigma_w_rad_s = 0;
  s.ext_velocity.resolution = 0;
  s.aps.rate_hz = 100;
  s.aps.sigma_m = 0;
  s.aps.resolution_m = 0;
  s.ground_truth.resolution_m = 0;
  s.ground_truth.resolution_rad = 0;
  return sc;
}

SlipEpisode episode(Kind kind, Wheel wheel, double t0, double t1, double s, double ramp = 0.2,
                    double brake = 0.0) {
  SlipEpisode e;
  e.kind = kind;
  e.wheel = wheel;
  e.t0_s = t0;
  e.t1_s = t1;
  e.s = s;
  e.ramp_s = ramp;
  e.brake_nm = brake;
  return e;
}

std::size_t row_at(const tracks::Track& tr, double t) {
  std::size_t i = 0;
  while (i + 1 < tr.size() && tr.t()[i] < t - 1e-9) ++i;
  return i;
}

// Steady-cruise motor power of one wheel (simulator.h: tau*omega + (tau/k_t)^2*R_coil)
// for a given torque.
double power_of(const RobotParams& r, double torque, double omega) {
  const double i = torque / r.torque_constant_nm_per_a;
  return torque * omega + i * i * r.coil_resistance_ohm;
}

// Every column, the ticks and the time of rows [0, end) are bit-identical.
void expect_rows_identical(const tracks::Track& a, const tracks::Track& b, std::size_t end) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < end; ++i) {
    ASSERT_EQ(a.t()[i], b.t()[i]);
    ASSERT_EQ(a.ticks_l()[i], b.ticks_l()[i]) << "row " << i;
    ASSERT_EQ(a.ticks_r()[i], b.ticks_r()[i]) << "row " << i;
    for (int c = 0; c < tracks::kNumCols; ++c) {
      const auto& ca = a.col(static_cast<tracks::Col>(c));
      const auto& cb = b.col(static_cast<tracks::Col>(c));
      ASSERT_EQ(ca.size(), cb.size());
      if (ca.empty() || std::isnan(ca[i])) continue;
      ASSERT_EQ(ca[i], cb[i]) << "column " << c << " row " << i;
    }
  }
}

double path_length(const tracks::Track& tr) {
  double d = 0;
  const auto& x = tr.col(tracks::Col::gt_x);
  const auto& y = tr.col(tracks::Col::gt_y);
  for (std::size_t i = 0; i + 1 < tr.size(); ++i) d += std::hypot(x[i + 1] - x[i], y[i + 1] - y[i]);
  return d;
}

TEST(SlipEpisodes, SpinKeepsTicksLowersPowerAndShortensTravel) {
  const Scenario base_sc = chair();
  Scenario sc = base_sc;
  const double s = 0.5, t0 = 5, t1 = 8, ramp = 0.2;
  sc.slip_episodes = {episode(Kind::spin, Wheel::left, t0, t1, s, ramp)};
  const tracks::Track base = simulate(base_sc), tr = simulate(sc);

  // Encoders count the rotation, which the spin does not touch.
  EXPECT_EQ(tr.ticks_l(), base.ticks_l());
  EXPECT_EQ(tr.ticks_r(), base.ticks_r());
  EXPECT_EQ(tr.col(tracks::Col::omega_l), base.col(tracks::Col::omega_l));
  // Everything up to the episode's start is the run without it.
  expect_rows_identical(base, tr, row_at(base, t0) + 1);

  // Mid-episode, steady cruise (a = alpha = 0 once the ramp is over): the left
  // wheel's Coulomb/rolling torque is scaled by 1 - s, the viscous one is not.
  const RobotParams& r = sc.robot;
  const double coulomb = r.coulomb_friction_nm * std::tanh(kOmega / r.coulomb_smoothing_rad_s);
  const double viscous = r.viscous_friction_nm_s * kOmega;
  const std::size_t mid = row_at(tr, 6.5);
  EXPECT_NEAR(base.col(tracks::Col::power_l)[mid], power_of(r, viscous + coulomb, kOmega), 1e-6);
  EXPECT_NEAR(tr.col(tracks::Col::power_l)[mid], power_of(r, viscous + (1 - s) * coulomb, kOmega), 1e-6);
  EXPECT_LT(tr.col(tracks::Col::power_l)[mid], 0.75 * base.col(tracks::Col::power_l)[mid]);
  EXPECT_NEAR(tr.col(tracks::Col::power_r)[mid], base.col(tracks::Col::power_r)[mid], 1e-6);  // the other wheel

  // The left ground speed is (1 - s(t))*u: the body covers
  // u/2 * integral of s(t) = u/2 * s*(T - ramp) less, and turns left by
  // u*s*(T - ramp)/D.
  const double lost = kSpeed * s * (t1 - t0 - ramp);
  EXPECT_NEAR(path_length(base) - path_length(tr), lost / 2, 2e-3);
  const std::size_t last = tr.size() - 1;
  EXPECT_NEAR(tr.col(tracks::Col::gt_theta)[last] - base.col(tracks::Col::gt_theta)[last], lost / 0.65, 2e-3);
  EXPECT_NEAR(base.col(tracks::Col::gt_theta)[last], 0.0, 1e-12);
}

TEST(SlipEpisodes, HoldLowersTicksRaisesPowerAndKeepsTheTruePath) {
  const Scenario base_sc = chair();
  Scenario sc = base_sc;
  const double s = 0.4, t0 = 5, t1 = 8, ramp = 0.2, brake = 20;
  sc.slip_episodes = {episode(Kind::hold, Wheel::left, t0, t1, s, ramp, brake)};
  const tracks::Track base = simulate(base_sc), tr = simulate(sc);

  expect_rows_identical(base, tr, row_at(base, t0) + 1);
  // The contact is dragged along: the true path, gyro and external velocity
  // are those of the run without the episode, everywhere.
  for (tracks::Col c : {tracks::Col::gt_x, tracks::Col::gt_y, tracks::Col::gt_theta, tracks::Col::gyro_z,
                        tracks::Col::v_ext, tracks::Col::w_ext, tracks::Col::aps_x})
    EXPECT_EQ(tr.col(c), base.col(c)) << static_cast<int>(c);
  EXPECT_EQ(tr.ticks_r(), base.ticks_r());

  // The left rotation is slowed by s(t): the encoders miss
  // s*omega*(T - ramp) rad of rotation.
  const std::size_t last = tr.size() - 1;
  const double missed_ticks = s * kOmega * (t1 - t0 - ramp) * 8800 / (2 * std::numbers::pi);
  EXPECT_NEAR(static_cast<double>(base.ticks_l()[last] - tr.ticks_l()[last]), missed_ticks, 2.0);

  const std::size_t mid = row_at(tr, 6.5);
  const double om = (1 - s) * kOmega;
  EXPECT_NEAR(tr.col(tracks::Col::omega_l)[mid], om, 1e-9);
  const RobotParams& r = sc.robot;
  const double torque = r.viscous_friction_nm_s * om +
                        r.coulomb_friction_nm * std::tanh(om / r.coulomb_smoothing_rad_s) +
                        brake * std::tanh(kOmega / r.coulomb_smoothing_rad_s);
  EXPECT_NEAR(tr.col(tracks::Col::power_l)[mid], power_of(r, torque, om), 1e-6);
  EXPECT_GT(tr.col(tracks::Col::power_l)[mid], 1.3 * base.col(tracks::Col::power_l)[mid]);
  EXPECT_NEAR(tr.col(tracks::Col::power_r)[mid], base.col(tracks::Col::power_r)[mid], 1e-6);
}

TEST(SlipEpisodes, StrengthRampsUpHoldsAndRampsDown) {
  const SlipEpisode e = episode(Kind::hold, Wheel::right, 5, 8, 0.6, 0.4, 10);
  EXPECT_EQ(episode_strength(e, 4.9), 0.0);
  EXPECT_EQ(episode_strength(e, 5.0), 0.0);
  EXPECT_NEAR(episode_strength(e, 5.1), 0.15, 1e-12);
  EXPECT_NEAR(episode_strength(e, 5.2), 0.30, 1e-12);
  EXPECT_NEAR(episode_strength(e, 5.4), 0.6, 1e-12);
  EXPECT_EQ(episode_strength(e, 6.5), 0.6);
  EXPECT_NEAR(episode_strength(e, 7.9), 0.15, 1e-12);
  EXPECT_EQ(episode_strength(e, 8.0), 0.0);
  EXPECT_EQ(episode_strength(e, 9.0), 0.0);

  const std::vector<SlipEpisode> list = {e, episode(Kind::spin, Wheel::left, 7, 10, 0.3)};
  EXPECT_EQ(slip_strength(list, 6.5, Wheel::right), 0.6);
  EXPECT_EQ(slip_strength(list, 6.5, Wheel::left), 0.0);
  EXPECT_EQ(slip_strength(list, 8.5, Wheel::left), 0.3);
  EXPECT_FALSE(slipping(list, 4.0));
  EXPECT_TRUE(slipping(list, 5.05));
  EXPECT_TRUE(slipping(list, 9.9));
  EXPECT_FALSE(slipping(list, 10.0));
  const SlipSchedule schedule(list);
  for (double t = 0; t < 11; t += 0.0137)
    for (Wheel w : {Wheel::left, Wheel::right})
      EXPECT_EQ(schedule.at(t, w).strength, slip_strength(list, t, w)) << t;

  // In the simulation: the hold's wheel rate follows the ramp (rows at 100 Hz).
  Scenario sc = chair();
  sc.slip_episodes = {episode(Kind::hold, Wheel::right, 5, 8, 0.6, 0.4, 10)};
  const tracks::Track tr = simulate(sc);
  for (double t : {5.0, 5.1, 5.2, 5.3, 6.0, 7.7, 8.0, 8.5})
    EXPECT_NEAR(tr.col(tracks::Col::omega_r)[row_at(tr, t)],
                kOmega * (1 - episode_strength(sc.slip_episodes[0], t)), 1e-9)
        << t;
}

TEST(SlipEpisodes, DefaultBrakeIsTwiceTheCoulombTorque) {
  Scenario a = chair(), b = chair();
  a.slip_episodes = {episode(Kind::hold, Wheel::left, 5, 8, 0.5)};
  b.slip_episodes = {episode(Kind::hold, Wheel::left, 5, 8, 0.5, 0.2, 2 * b.robot.coulomb_friction_nm)};
  const tracks::Track ta = simulate(a), tb = simulate(b);
  EXPECT_EQ(ta.col(tracks::Col::power_l), tb.col(tracks::Col::power_l));
  EXPECT_EQ(ta.ticks_l(), tb.ticks_l());
  Scenario none = chair();
  EXPECT_NE(ta.col(tracks::Col::power_l), simulate(none).col(tracks::Col::power_l));
}

TEST(SlipEpisodes, EpisodesOnBothWheelsMayOverlap) {
  Scenario sc = chair();
  sc.slip_episodes = {episode(Kind::hold, Wheel::right, 6, 9, 0.5, 0.2, 15),
                      episode(Kind::spin, Wheel::left, 5, 8, 0.5)};
  std::string why;
  ASSERT_TRUE(validate_scenario(sc, &why)) << why;
  const tracks::Track base = simulate(chair()), tr = simulate(sc);
  EXPECT_EQ(tr.ticks_l(), base.ticks_l());                       // spin: rotation untouched
  EXPECT_LT(tr.ticks_r().back() + 1000, base.ticks_r().back());  // hold: counts missed
  const std::size_t both = row_at(tr, 7);
  EXPECT_LT(tr.col(tracks::Col::power_l)[both], base.col(tracks::Col::power_l)[both]);
  EXPECT_GT(tr.col(tracks::Col::power_r)[both], base.col(tracks::Col::power_r)[both]);
}

TEST(SlipEpisodes, MetadataTextIsExactAndRoundTrips) {
  const std::vector<SlipEpisode> list = {episode(Kind::spin, Wheel::left, 40, 44, 0.6),
                                         episode(Kind::hold, Wheel::right, 70.125, 73, 0.5, 0.25, 6)};
  EXPECT_EQ(format_slip_episodes(list), "spin:wheel=left,t0_s=40,t1_s=44,s=0.6,ramp_s=0.2; "
                                        "hold:wheel=right,t0_s=70.125,t1_s=73,s=0.5,ramp_s=0.25,brake_nm=6");
  EXPECT_EQ(format_slip_episodes({}), "none");
  EXPECT_TRUE(parse_slip_episodes("none").empty());
  EXPECT_TRUE(parse_slip_episodes("").empty());

  // Awkward doubles come back bit for bit.
  const std::vector<SlipEpisode> odd = {
      episode(Kind::hold, Wheel::left, 0.1 + 0.2, 1.0 / 3.0 + 2, 0.1 * 3, 0.7 / 7, 12.000000000000002),
      episode(Kind::spin, Wheel::right, 1e-3, 123.456789012345, 0.9)};
  const std::vector<SlipEpisode> back = parse_slip_episodes(format_slip_episodes(odd));
  ASSERT_EQ(back.size(), odd.size());
  for (std::size_t i = 0; i < odd.size(); ++i) {
    EXPECT_EQ(back[i].kind, odd[i].kind);
    EXPECT_EQ(back[i].wheel, odd[i].wheel);
    EXPECT_EQ(back[i].t0_s, odd[i].t0_s);
    EXPECT_EQ(back[i].t1_s, odd[i].t1_s);
    EXPECT_EQ(back[i].s, odd[i].s);
    EXPECT_EQ(back[i].ramp_s, odd[i].ramp_s);
    EXPECT_EQ(back[i].brake_nm, odd[i].brake_nm);
  }
  // Spaces and the optional keys' defaults.
  const auto defaults = parse_slip_episodes(" hold : wheel = left , t0_s=1, t1_s=2 ,s=0.5 ");
  ASSERT_EQ(defaults.size(), 1u);
  EXPECT_EQ(defaults[0].ramp_s, 0.2);
  EXPECT_EQ(defaults[0].brake_nm, 0.0);

  // Through a simulated track and its file.
  Scenario sc = chair();
  sc.slip_episodes = {episode(Kind::spin, Wheel::left, 5, 8, 0.5),
                      episode(Kind::hold, Wheel::right, 2.5, 4.25, 0.3)};
  std::ostringstream file;
  tracks::format_track(simulate(sc), file);
  EXPECT_THAT(file.str(), HasSubstr("sim.slip_episodes: spin:wheel=left,t0_s=5,t1_s=8,s=0.5,ramp_s=0.2; "
                                    "hold:wheel=right,t0_s=2.5,t1_s=4.25,s=0.3,ramp_s=0.2,brake_nm=0\n"));
  std::istringstream in(file.str());
  const tracks::Track read = tracks::parse_track(in, "t.csv");
  const auto from_meta = slip_episodes_from_metadata(read.meta());
  ASSERT_EQ(from_meta.size(), 2u);
  EXPECT_EQ(format_slip_episodes(from_meta), format_slip_episodes(sc.slip_episodes));
  // Without episodes the key is not written (older tracks keep their bytes).
  std::ostringstream plain;
  tracks::format_track(simulate(chair()), plain);
  EXPECT_THAT(plain.str(), Not(HasSubstr("slip_episodes")));
  EXPECT_TRUE(slip_episodes_from_metadata(simulate(chair()).meta()).empty());
}

TEST(SlipEpisodes, BadTextGivesOneLineErrors) {
  auto error_of = [](const std::string& text) {
    try {
      (void)parse_slip_episodes(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string ok = "wheel=left,t0_s=1,t1_s=2,s=0.5";
  EXPECT_THAT(error_of("slide:" + ok), AllOf(HasSubstr("slip episode 1"), HasSubstr("kind 'slide'"),
                                             HasSubstr("expected spin or hold")));
  EXPECT_THAT(error_of("spin:wheel=middle,t0_s=1,t1_s=2,s=0.5"),
              AllOf(HasSubstr("wheel = 'middle'"), HasSubstr("left or right")));
  EXPECT_THAT(error_of("spin:wheel=left,t0_s=1,t1_s=2"), HasSubstr("missing s"));
  EXPECT_THAT(error_of("spin:" + ok + ",s=0.4"), HasSubstr("s given twice"));
  EXPECT_THAT(error_of("spin:wheel=left,t0_s=one,t1_s=2,s=0.5"), HasSubstr("t0_s = 'one' is not a number"));
  EXPECT_THAT(error_of("spin:" + ok + ",brake_nm=3"), HasSubstr("unknown key 'brake_nm'"));
  EXPECT_THAT(error_of("spin:" + ok + ",grip=3"), HasSubstr("unknown key 'grip'"));
  EXPECT_THAT(error_of("spin:" + ok + ",ramp_s"), HasSubstr("'ramp_s' is not KEY=VALUE"));
  EXPECT_THAT(error_of("spin"), HasSubstr("no parameters"));
  EXPECT_THAT(error_of("spin:" + ok + ";; hold:" + ok), HasSubstr("slip episode 2: empty"));
  EXPECT_THAT(error_of("spin:wheel=left,t0_s=1,t1_s=2,s=1.5"),
              AllOf(StartsWith("slip_episodes[1]: s = 1.5"), HasSubstr("(0, 0.9]")));
  EXPECT_THAT(error_of("spin:" + ok + "; hold:wheel=left,t0_s=1.5,t1_s=3,s=0.5"),
              AllOf(HasSubstr("slip_episodes[2]"), HasSubstr("overlaps slip_episodes[1]"),
                    HasSubstr("left wheel")));
  for (const std::string& bad :
       std::vector<std::string>{"slide:" + ok, "spin:" + ok + ",s=0.4", "spin:wheel=left,t0_s=1,t1_s=2,s=2"})
    EXPECT_THAT(error_of(bad), Not(HasSubstr("\n")));

  tracks::TrackMeta meta;
  meta.extra = {{"sim.slip_episodes", "spin:wheel=up"}};
  try {
    (void)slip_episodes_from_metadata(meta);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), AllOf(StartsWith("sim.slip_episodes: "), HasSubstr("wheel = 'up'")));
  }
}

TEST(SlipEpisodes, ValidationNamesEpisodeFieldValueAndExpectation) {
  auto why_of = [](std::vector<SlipEpisode> list) {
    Scenario sc = chair();
    sc.slip_episodes = std::move(list);
    std::string why;
    EXPECT_FALSE(validate_scenario(sc, &why));
    EXPECT_THROW((void)simulate(sc), std::invalid_argument);
    return why;
  };
  EXPECT_THAT(
      why_of({episode(Kind::spin, Wheel::left, 5, 8, 0.3), episode(Kind::hold, Wheel::right, 1, 2, 0.95)}),
      AllOf(StartsWith("slip_episodes[2]: s = 0.95"), HasSubstr("(0, 0.9]")));
  EXPECT_THAT(why_of({episode(Kind::spin, Wheel::left, 5, 8, 0.0)}), StartsWith("slip_episodes[1]: s = 0;"));
  EXPECT_THAT(why_of({episode(Kind::spin, Wheel::left, 5, 5.3, 0.5, 0.2)}),
              AllOf(StartsWith("slip_episodes[1]: ramp_s = 0.2"), HasSubstr("2*ramp_s <= t1_s - t0_s")));
  EXPECT_THAT(why_of({episode(Kind::spin, Wheel::left, 5, 8, 0.5, 0.0)}),
              StartsWith("slip_episodes[1]: ramp_s = 0;"));
  EXPECT_THAT(why_of({episode(Kind::spin, Wheel::left, 5, 4, 0.5)}),
              AllOf(StartsWith("slip_episodes[1]: t1_s = 4"), HasSubstr("> t0_s = 5")));
  EXPECT_THAT(why_of({episode(Kind::spin, Wheel::left, -1, 4, 0.5)}),
              StartsWith("slip_episodes[1]: t0_s = -1"));
  EXPECT_THAT(why_of({episode(Kind::hold, Wheel::left, 1, 4, 0.5, 0.2, -2)}),
              StartsWith("slip_episodes[1]: brake_nm = -2"));
  EXPECT_THAT(why_of({episode(Kind::spin, Wheel::left, 1, 4, 0.5, 0.2, 2)}),
              AllOf(StartsWith("slip_episodes[1]: brake_nm = 2"), HasSubstr("hold episodes only")));
  EXPECT_THAT(why_of({episode(Kind::spin, Wheel::left, 1, 4, std::nan(""))}),
              StartsWith("slip_episodes[1]: s = nan"));
  EXPECT_THAT(why_of({episode(Kind::spin, Wheel::left, 100, 104, 0.5)}),
              AllOf(StartsWith("slip_episodes[1]: t0_s = 100"), HasSubstr("end of the motion")));
  SlipEpisode odd = episode(Kind::spin, Wheel::left, 1, 4, 0.5);
  odd.wheel = static_cast<Wheel>(7);
  EXPECT_THAT(why_of({odd}), StartsWith("slip_episodes[1]: wheel = 7"));
  // Same wheel overlapping: both named, whatever the list order; touching is fine.
  SlipEpisode first = episode(Kind::hold, Wheel::right, 2, 6, 0.5);
  first.line = 12;
  EXPECT_THAT(
      why_of({first, episode(Kind::spin, Wheel::left, 1, 3, 0.5),
              episode(Kind::spin, Wheel::right, 5, 9, 0.5)}),
      AllOf(
          StartsWith("slip_episodes[3] ([5, 9] s) overlaps slip_episodes[1] (line 12) ([2, 6] s) on the right "
                     "wheel"),
          HasSubstr("not to overlap")));
  EXPECT_THAT(
      why_of({episode(Kind::spin, Wheel::left, 5, 9, 0.5), episode(Kind::spin, Wheel::left, 1, 12, 0.5)}),
      StartsWith("slip_episodes[2] ([1, 12] s) overlaps slip_episodes[1]"));
  Scenario touching = chair();
  touching.slip_episodes = {episode(Kind::spin, Wheel::left, 2, 5, 0.5),
                            episode(Kind::hold, Wheel::left, 5, 8, 0.5)};
  std::string why;
  EXPECT_TRUE(validate_scenario(touching, &why)) << why;
}

TEST(SlipEpisodes, SameSeedSameTrack) {
  Scenario sc = chair();
  sc.sensors.power.sigma_w = 0.5;
  sc.sensors.gyro.sigma_rad_s = 0.002;
  sc.sensors.ext_velocity.sigma_v_m_s = 0.02;
  sc.slip_episodes = {episode(Kind::spin, Wheel::left, 3, 6, 0.6),
                      episode(Kind::hold, Wheel::right, 7, 10, 0.4, 0.3, 12)};
  auto text = [](const Scenario& s) {
    std::ostringstream out;
    tracks::format_track(simulate(s), out);
    return out.str();
  };
  const std::string a = text(sc);
  EXPECT_EQ(a, text(sc));
  Scenario other = sc;
  other.seed = 8;
  EXPECT_NE(a, text(other));
}

}  // namespace
}  // namespace odotune::sim

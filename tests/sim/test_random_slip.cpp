// Random slip-episode layouts (odotune/sim/random_slip.h): valid, inside moving
// stretches, within the option ranges, both kinds and wheels, seeded, and
// bad options refused with the field named.
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/sim/motion_profile.h>
#include <odotune/sim/random_slip.h>
#include <odotune/sim/slip_episodes.h>

namespace odotune::sim {
namespace {

using ::testing::HasSubstr;
using Kind = SlipEpisode::Kind;
using Wheel = SlipEpisode::Wheel;

Segment slip_straight(double distance_m, double speed_m_s) {
  Segment s;
  s.kind = Segment::Kind::straight;
  s.distance_m = distance_m;
  s.speed_m_s = speed_m_s;
  return s;
}
Segment slip_stop(double duration_s) {
  Segment s;
  s.kind = Segment::Kind::stop;
  s.duration_s = duration_s;
  return s;
}
Segment slip_spin(double angle_deg, double rate_deg_s) {
  Segment s;
  s.kind = Segment::Kind::spin;
  s.angle_deg = angle_deg;
  s.rate_deg_s = rate_deg_s;
  return s;
}

// ~3 minutes: fast and slow straights, spins on the spot and stops between.
MotionParams slip_motion() {
  MotionParams m;
  m.max_accel_m_s2 = 0.45;
  m.max_angular_accel_rad_s2 = 1.2;
  for (int i = 0; i < 6; ++i) {
    m.segments.push_back(slip_straight(18.0, 0.9));
    m.segments.push_back(slip_stop(3.0));
    m.segments.push_back(slip_spin(90.0, 45.0));
    m.segments.push_back(slip_straight(3.0, 0.2));  // too slow for an episode
  }
  return m;
}

TEST(RandomSlip, EpisodesAreValidInsideMovingStretchesAndWithinTheRanges) {
  const MotionProfile profile(slip_motion());
  const RandomSlipOptions o;
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
    SCOPED_TRACE(seed);
    const std::vector<SlipEpisode> e = random_slip_episodes(profile, seed, o);
    ASSERT_GE(e.size(), 6u);  // ~180 s of drive, one every 6-15 s where it moves
    std::string why;
    EXPECT_TRUE(validate_slip_episodes(e, &why)) << why;
    for (std::size_t i = 0; i < e.size(); ++i) {
      const double d = e[i].t1_s - e[i].t0_s;
      EXPECT_GE(d, o.min_duration_s);
      EXPECT_LE(d, o.max_duration_s);
      EXPECT_GE(e[i].s, o.min_strength);
      EXPECT_LE(e[i].s, o.max_strength);
      EXPECT_GE(e[i].t0_s, o.first_s);
      EXPECT_LE(e[i].t1_s, profile.duration_s() - o.end_margin_s);
      for (double t = e[i].t0_s; t <= e[i].t1_s; t += 0.01)
        ASSERT_GE(std::abs(profile.at(t).v_m_s), o.min_speed_m_s) << "episode " << i << " at t = " << t;
      if (e[i].kind == Kind::hold) {
        EXPECT_NEAR(e[i].brake_nm, o.hold_brake_per_s_nm * e[i].s + o.hold_brake_offset_nm, 1e-12);
      } else {
        EXPECT_EQ(e[i].brake_nm, 0.0);
      }
      EXPECT_NEAR(e[i].ramp_s, 0.2 + o.ramp_per_strength_s * std::max(0.0, e[i].s - 0.5), 1e-12);
      if (i > 0) {
        EXPECT_GE(e[i].t0_s - e[i - 1].t1_s, o.min_gap_s);
      }
    }
  }
}

TEST(RandomSlip, LayoutsMixKindsAndWheelsAndDependOnlyOnTheSeed) {
  const MotionProfile profile(slip_motion());
  std::set<std::pair<int, int>> seen;  // (kind, wheel)
  for (std::uint64_t seed = 0; seed < 8; ++seed)
    for (const SlipEpisode& e : random_slip_episodes(profile, seed))
      seen.insert({static_cast<int>(e.kind), static_cast<int>(e.wheel)});
  EXPECT_EQ(seen.size(), 4u);  // spin/hold × left/right

  const auto text = [&](std::uint64_t seed) {
    return format_slip_episodes(random_slip_episodes(profile, seed));
  };
  EXPECT_EQ(text(7), text(7));
  EXPECT_NE(text(7), text(8));
}

TEST(RandomSlip, ADriveWithoutAMovingStretchGetsNoEpisode) {
  MotionParams m;
  m.segments = {slip_stop(5.0), slip_straight(2.0, 0.2), slip_stop(5.0), slip_spin(180.0, 45.0),
                slip_stop(20.0)};
  EXPECT_TRUE(random_slip_episodes(MotionProfile(m), 3).empty());
}

TEST(RandomSlip, BadOptionsAreRefusedNamingTheField) {
  const MotionProfile profile(slip_motion());
  const auto message = [&](const RandomSlipOptions& o) {
    try {
      random_slip_episodes(profile, 1, o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(nothing thrown)");
  };
  RandomSlipOptions o;
  o.max_strength = 0.95;
  EXPECT_THAT(message(o), HasSubstr("max_strength = 0.95"));
  o = {};
  o.min_duration_s = 6.0;  // above max_duration_s
  EXPECT_THAT(message(o), HasSubstr("min_duration_s = 6"));
  o = {};
  o.min_gap_s = std::nan("");
  EXPECT_THAT(message(o), HasSubstr("min_gap_s"));
  o = {};
  o.hold_brake_offset_nm = -20.0;  // a negative brake at s = 0.3
  EXPECT_THAT(message(o), HasSubstr("hold_brake_offset_nm = -20"));
}

}  // namespace
}  // namespace odotune::sim

// Test helper for the velocity-fusion tests (fusion_input.h, ukf_fusion.h,
// ukf_objective.h): a small simulated drive built in memory through the
// project's simulator (odotune/sim/simulator.h): 1 s at rest, a straight, a left
// arc, a spin on the spot, a second straight, 1 s at rest. Default robot
// (80 mm wheels, 0.42 m base, 2048 counts/rev), every sensor on: encoders,
// commands, gyro and power at 100 Hz, the external velocity sensor at 10 Hz
// (σ 0.02 m/s and 0.02 rad/s), ground truth at 100 Hz.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <odotune/sim/effects.h>
#include <odotune/sim/scenario.h>
#include <odotune/sim/simulator.h>
#include <odotune/tracks/track.h>

namespace odotune::testing_support {

struct FusionTrackOptions {
  std::string name = "fusion";
  std::uint64_t seed = 1;
  double wheel_radius_m = 0.08, wheel_base_m = 0.42, ticks_per_rev = 2048;
  // The drive's cruise commands (the steady values tests compare with).
  double straight_speed_m_s = 0.5;  // both straights
  double straight_m = 2.0;          // first straight; the second is half
  double arc_radius_m = 1.0, arc_deg = 90.0, arc_speed_m_s = 0.4;
  double spin_deg = 90.0, spin_rate_deg_s = 45.0;
  double max_accel_m_s2 = 0.5, max_angular_accel_rad_s2 = 2.0;
  int laps = 1;  // the four moving segments, repeated
  double gyro_sigma_rad_s = 0.002;
  double ext_sigma_v_m_s = 0.02, ext_sigma_w_rad_s = 0.02;
  bool ext = true, gyro = true, power = true, gt = true;
  std::vector<std::string> effects;  // odotune/sim/effects.h syntax
};

inline sim::Scenario fusion_scenario(const FusionTrackOptions& o) {
  sim::Scenario sc;
  sc.name = o.name;
  sc.seed = o.seed;
  sc.robot.wheel_radius_left_m = sc.robot.wheel_radius_right_m = o.wheel_radius_m;
  sc.robot.wheel_base_m = o.wheel_base_m;
  sc.robot.ticks_per_rev = o.ticks_per_rev;
  sc.motion.max_accel_m_s2 = o.max_accel_m_s2;
  sc.motion.max_angular_accel_rad_s2 = o.max_angular_accel_rad_s2;
  using K = sim::Segment::Kind;
  auto seg = [](K kind) {
    sim::Segment s;
    s.kind = kind;
    return s;
  };
  std::vector<sim::Segment>& v = sc.motion.segments;
  sim::Segment stop = seg(K::stop);
  stop.duration_s = 1.0;
  v.push_back(stop);
  for (int lap = 0; lap < o.laps; ++lap) {
    sim::Segment s1 = seg(K::straight);
    s1.distance_m = o.straight_m;
    s1.speed_m_s = o.straight_speed_m_s;
    sim::Segment arc = seg(K::arc);
    arc.radius_m = o.arc_radius_m;
    arc.angle_deg = o.arc_deg;
    arc.speed_m_s = o.arc_speed_m_s;
    sim::Segment spin = seg(K::spin);
    spin.angle_deg = o.spin_deg;
    spin.rate_deg_s = o.spin_rate_deg_s;
    sim::Segment s2 = s1;
    s2.distance_m = 0.5 * o.straight_m;
    v.insert(v.end(), {s1, arc, spin, s2});
  }
  v.push_back(stop);

  auto& s = sc.sensors;
  s.encoders.enabled = true;
  s.encoders.rate_hz = 100.0;
  s.commands.enabled = true;
  s.commands.rate_hz = 100.0;
  s.gyro.enabled = o.gyro;
  s.gyro.rate_hz = 100.0;
  s.gyro.sigma_rad_s = o.gyro_sigma_rad_s;
  s.power.enabled = o.power;
  s.power.rate_hz = 100.0;
  s.ext_velocity.enabled = o.ext;
  s.ext_velocity.rate_hz = 10.0;
  s.ext_velocity.sigma_v_m_s = o.ext_sigma_v_m_s;
  s.ext_velocity.sigma_w_rad_s = o.ext_sigma_w_rad_s;
  s.aps.enabled = false;
  s.ground_truth.enabled = o.gt;
  s.ground_truth.rate_hz = 100.0;
  for (const auto& e : o.effects) sim::apply_effect(sc.effects, sim::parse_effect_spec(e));
  return sc;
}

inline tracks::Track fusion_track(const FusionTrackOptions& o) { return sim::simulate(fusion_scenario(o)); }

}  // namespace odotune::testing_support

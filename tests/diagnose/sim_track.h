// Test helper: a simulated Track built in memory (no files) from a built-in
// base motion, a robot, sensor rates/noise, effect specs and a seed, through
// the project's simulator (odotune/sim/simulator.h).
//
// Base motion: 1 s at rest, then laps of a closed ~5.6 m x 3.4 m circuit
// repeated until the motion lasts at least duration_s, then 1 s at rest. One
// lap (~38 s) starts at the origin heading +x and holds: a lane change left and
// back on the first side (arcs of 1 m radius, +-30 deg, right turns included),
// straights at 0.5-0.8 m/s, four 90-deg left corners of 0.6 m radius, a stop
// mid-way along the second side, and a spin of +180 deg then -180 deg mid-way
// along the third. The first side runs along y ~ 0 (lane change at y ~ 0.27
// for x ~ 2.0-2.6), so a box around x in [1.8, 2.6] is crossed on every lap.
//
// Default robot: 80 mm wheels, 0.42 m base, 2048 counts/rev (not one of the
// reference tracks' robots). Power and external-velocity sensors are off.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <odotune/sim/effects.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/scenario.h>
#include <odotune/sim/simulator.h>
#include <odotune/tracks/track.h>

namespace odotune::testing_support {

struct SimTrackOptions {
  double duration_s = 120.0;  // minimum motion length [s]
  double wheel_radius_left_m = 0.08, wheel_radius_right_m = 0.08;
  double wheel_base_m = 0.42, ticks_per_rev = 2048;
  double odo_rate_hz = 100.0;                             // encoders and commands [Hz]
  bool encoders = true;                                   // false: the odometry is v_cmd/w_cmd only
  bool omega = false;                                     // also write omega_l/omega_r
  double gyro_rate_hz = 100.0, gyro_sigma_rad_s = 0.002;  // rate 0 = no gyro
  double gt_rate_hz = 100.0, gt_sigma_m = 0.0;            // rate 0 = no ground truth
  double aps_rate_hz = 0.0, aps_sigma_m = 0.05;           // rate 0 = no fixes
  std::vector<std::string> effects;  // "lateral_skid:k=0.03" (odotune/sim/effects.h syntax)
  std::uint64_t seed = 1;
};

namespace sim_track_detail {
inline sim::Segment seg(sim::Segment::Kind kind, double a, double b, double c = 0.0) {
  sim::Segment s;
  s.kind = kind;
  using K = sim::Segment::Kind;
  if (kind == K::straight) s.distance_m = a, s.speed_m_s = b;
  if (kind == K::arc) s.radius_m = a, s.angle_deg = b, s.speed_m_s = c;
  if (kind == K::spin) s.angle_deg = a, s.rate_deg_s = b;
  if (kind == K::stop) s.duration_s = a;
  return s;
}
inline void append_lap(std::vector<sim::Segment>& v) {
  using K = sim::Segment::Kind;
  const std::vector<sim::Segment> lap = {
      seg(K::straight, 1.0, 0.6), seg(K::arc, 1.0, 30, 0.5),  seg(K::arc, 1.0, -30, 0.5),
      seg(K::straight, 0.6, 0.7), seg(K::arc, 1.0, -30, 0.5), seg(K::arc, 1.0, 30, 0.5),
      seg(K::straight, 0.8, 0.6), seg(K::arc, 0.6, 90, 0.4),  seg(K::straight, 0.8, 0.5),
      seg(K::stop, 1.0, 0),       seg(K::straight, 0.8, 0.5), seg(K::arc, 0.6, 90, 0.4),
      seg(K::straight, 2.2, 0.8), seg(K::spin, 180, 90),      seg(K::spin, -180, 90),
      seg(K::straight, 2.2, 0.8), seg(K::arc, 0.6, 90, 0.4),  seg(K::straight, 1.6, 0.5),
      seg(K::arc, 0.6, 90, 0.4)};
  v.insert(v.end(), lap.begin(), lap.end());
}
}  // namespace sim_track_detail

inline sim::Scenario sim_scenario(const SimTrackOptions& o) {
  using namespace sim_track_detail;
  sim::Scenario sc;
  sc.name = "sim_track";
  sc.seed = o.seed;
  sc.robot.wheel_radius_left_m = o.wheel_radius_left_m;
  sc.robot.wheel_radius_right_m = o.wheel_radius_right_m;
  sc.robot.wheel_base_m = o.wheel_base_m;
  sc.robot.ticks_per_rev = o.ticks_per_rev;
  using K = sim::Segment::Kind;
  for (int laps = 1;; ++laps) {
    std::vector<sim::Segment> segs = {seg(K::stop, 1.0, 0)};
    for (int i = 0; i < laps; ++i) append_lap(segs);
    segs.push_back(seg(K::stop, 1.0, 0));
    sc.motion.segments = segs;
    if (sim::MotionProfile(sc.motion).duration_s() >= o.duration_s || laps > 1000) break;
  }
  auto& s = sc.sensors;
  s.encoders.enabled = o.encoders;
  s.encoders.rate_hz = o.odo_rate_hz;
  s.encoders.omega = o.omega;
  s.commands.rate_hz = o.odo_rate_hz;
  s.gyro.enabled = o.gyro_rate_hz > 0;
  s.gyro.rate_hz = o.gyro_rate_hz > 0 ? o.gyro_rate_hz : 100.0;
  s.gyro.sigma_rad_s = o.gyro_sigma_rad_s;
  s.power.enabled = false;
  s.ext_velocity.enabled = false;
  s.aps.enabled = o.aps_rate_hz > 0;
  s.aps.rate_hz = o.aps_rate_hz > 0 ? o.aps_rate_hz : 1.0;
  s.aps.sigma_m = o.aps_sigma_m;
  s.ground_truth.enabled = o.gt_rate_hz > 0;
  s.ground_truth.rate_hz = o.gt_rate_hz > 0 ? o.gt_rate_hz : 100.0;
  s.ground_truth.sigma_m = o.gt_sigma_m;
  for (const auto& e : o.effects) sim::apply_effect(sc.effects, sim::parse_effect_spec(e));
  return sc;
}

inline tracks::Track simulate_track(const SimTrackOptions& o) { return sim::simulate(sim_scenario(o)); }

}  // namespace odotune::testing_support

// Test helper for the odometry calibration tests: a simulated wheelchair-like
// robot (Fariña, Toledo & Acosta, RA-L 2026, §IV.A: R = 0.32 m, 8800 counts
// per wheel revolution; D = 0.65 m) driving the laps of
// ../diagnose/sim_track.h, with encoders and ground truth at 100 Hz and the
// external body-velocity sensor at 10 Hz (σ 0.02 m/s and 0.02 rad/s unless
// told otherwise). Built in memory through the project's simulator.
#pragma once

#include <string>
#include <vector>

#include <odotune/filters/odometry_params.h>

#include "diagnose/sim_track.h"

namespace odotune::testing_support {

inline constexpr double kChairRadiusM = 0.32;
inline constexpr double kChairBaseM = 0.65;

struct ChairTrackOptions {
  double duration_s = 120.0;
  std::vector<std::string> effects;  // odotune/sim/effects.h syntax
  double ext_sigma_v_m_s = 0.02;
  double ext_sigma_w_rad_s = 0.02;
  bool ext = true;  // external velocity sensor on
  bool gt = true;   // ground truth on
  std::uint64_t seed = 7;
};

inline sim::Scenario chair_scenario(const ChairTrackOptions& o) {
  SimTrackOptions s;
  s.duration_s = o.duration_s;
  s.wheel_radius_left_m = s.wheel_radius_right_m = kChairRadiusM;
  s.wheel_base_m = kChairBaseM;
  s.ticks_per_rev = 8800;
  s.odo_rate_hz = 100.0;
  s.gt_rate_hz = o.gt ? 100.0 : 0.0;
  s.effects = o.effects;
  s.seed = o.seed;
  sim::Scenario sc = sim_scenario(s);
  sc.name = "chair";
  sc.sensors.ext_velocity.enabled = o.ext;
  sc.sensors.ext_velocity.rate_hz = 10.0;
  sc.sensors.ext_velocity.sigma_v_m_s = o.ext_sigma_v_m_s;
  sc.sensors.ext_velocity.sigma_w_rad_s = o.ext_sigma_w_rad_s;
  return sc;
}

inline tracks::Track chair_track(const ChairTrackOptions& o) { return sim::simulate(chair_scenario(o)); }

// The misaligned chair the calibration tests recover: left radius × 0.99,
// right × 1.012, wheel base × 1.02.
inline constexpr double kMisalignedScaleL = 0.99, kMisalignedScaleR = 1.012, kMisalignedScaleBase = 1.02;
inline ChairTrackOptions misaligned_chair(double duration_s, std::uint64_t seed) {
  ChairTrackOptions o;
  o.duration_s = duration_s;
  o.seed = seed;
  o.effects = {"radius_error:scale_l=0.99,scale_r=1.012", "wheel_base_error:scale=1.02"};
  return o;
}

// The true parameters of radius_error / wheel_base_error scales (computed
// here from the scales, independently of the code under test).
inline filters::OdometryParams chair_truth(double scale_l, double scale_r, double scale_base) {
  filters::OdometryParams p;
  p.wheel_radius_left_m = kChairRadiusM * scale_l;
  p.wheel_radius_right_m = kChairRadiusM * scale_r;
  p.wheel_base_m = kChairBaseM * scale_base;
  return p;
}

}  // namespace odotune::testing_support

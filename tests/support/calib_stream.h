// A synthetic calibration sample stream for the calibrator tests: a varied
// drive (speed changes, turns both ways, spins on the spot) of a
// differential-drive robot with known wheel radii and wheel base, measured at
// a fixed rate with Gaussian noise on V and W (seeded).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include <odotune/filters/odometry_params.h>
#include <odotune/sim/normal_rng.h>

namespace odotune::filters::testing {

struct StreamSpec {
  OdometryParams truth{0.326, 0.318, 0.65};  // R_L, R_R, D [m]
  double duration_s = 60.0;
  double rate_hz = 10.0;
  double noise_sd = 0.02;  // σ of V [m/s] and W [rad/s]
  std::uint64_t seed = 11;
  // From step_time_s on, both radii are multiplied by step_factor.
  double step_time_s = 1e300;
  double step_factor = 1.0;
};

struct Stream {
  std::vector<CalibSample> samples;
  std::vector<double> t;              // time of each sample [s]
  std::vector<OdometryParams> truth;  // the true parameters at each sample
};

// Commanded body velocities at time t: a slow speed cycle with a turn
// profile alternating left and right, and a 3 s spin on the spot (alternating
// direction) every 20 s.
inline BodyVelocity drive_profile(double t) {
  const double two_pi = 2.0 * std::numbers::pi;
  BodyVelocity u{0.5 + 0.4 * std::sin(two_pi * t / 23.0), 0.9 * std::sin(two_pi * t / 13.0)};
  const double phase = std::fmod(t, 20.0);
  if (phase >= 15.0 && phase < 18.0) {
    const bool left = static_cast<long>(t / 20.0) % 2 == 0;
    u = {0.05, left ? 1.2 : -1.2};
  }
  return u;
}

inline Stream make_stream(const StreamSpec& spec) {
  Stream out;
  sim::Normal normal(spec.seed);
  const double dt = 1.0 / spec.rate_hz;
  const auto count = static_cast<long>(std::floor(spec.duration_s * spec.rate_hz));
  for (long k = 0; k < count; ++k) {
    const double t = static_cast<double>(k) * dt;
    OdometryParams p = spec.truth;
    if (t >= spec.step_time_s) {
      p.wheel_radius_left_m *= spec.step_factor;
      p.wheel_radius_right_m *= spec.step_factor;
    }
    const BodyVelocity u = drive_profile(t);
    CalibSample s;
    s.dt_s = k == 0 ? 0.0 : dt;
    s.omega_r_rad_s = (u.v_m_s + 0.5 * u.w_rad_s * p.wheel_base_m) / p.wheel_radius_right_m;
    s.omega_l_rad_s = (u.v_m_s - 0.5 * u.w_rad_s * p.wheel_base_m) / p.wheel_radius_left_m;
    s.v_m_s = u.v_m_s + spec.noise_sd * normal();
    s.w_rad_s = u.w_rad_s + spec.noise_sd * normal();
    s.v_var = spec.noise_sd * spec.noise_sd;
    s.w_var = spec.noise_sd * spec.noise_sd;
    out.samples.push_back(s);
    out.t.push_back(t);
    out.truth.push_back(p);
  }
  return out;
}

// Largest relative error of the two radii.
inline double radius_error(const OdometryParams& estimate, const OdometryParams& truth) {
  return std::max(std::abs(estimate.wheel_radius_left_m / truth.wheel_radius_left_m - 1.0),
                  std::abs(estimate.wheel_radius_right_m / truth.wheel_radius_right_m - 1.0));
}

}  // namespace odotune::filters::testing

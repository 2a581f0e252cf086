// A track laid out for the sim-to-real diagnosis (docs/diagnosis-design.md):
// the odometry as measured, the gyro, the nominal robot and the reference,
// as plain arrays in SI units. Built once per track; the diagnosis never
// touches the Track again.
#pragma once

#include <string>
#include <vector>

#include "tracks/track.h"

namespace odotune::diagnose {

enum class OdometryKind {
  wheel_angles,   // cumulative wheel rotation [rad] (from ticks, or integrated omega_l/r)
  body_velocity,  // body velocities v [m/s], w [rad/s] (v_cmd/w_cmd: commanded or base-reported)
};

enum class ReferenceKind {
  gt,   // ground-truth poses (x, y, θ)
  aps,  // absolute position fixes only (heading unknown)
};

struct DiagInput {
  std::string track_name;

  // Nominal robot (track metadata; body_velocity tracks may lack radii).
  double radius_l_m = 0.0, radius_r_m = 0.0, wheel_base_m = 0.0;

  // Odometry samples, strictly increasing time.
  OdometryKind odometry = OdometryKind::wheel_angles;
  std::vector<double> odo_t_s;
  std::vector<double> phi_l_rad, phi_r_rad;  // wheel_angles: rotation since the first sample
  std::vector<double> v_mps, w_radps;        // body_velocity: value held from its stamp to the next

  // Commanded body velocities when the track has them alongside wheel odometry
  // (for actuator_lag), same times as odo_t_s; empty otherwise.
  std::vector<double> cmd_v_mps, cmd_w_radps;

  // Gyro (empty when the track has none).
  std::vector<double> gyro_t_s, gyro_z_radps;

  // Reference samples, strictly increasing time, within the odometry's span.
  ReferenceKind reference = ReferenceKind::gt;
  std::vector<double> ref_t_s, ref_x_m, ref_y_m;
  std::vector<double> ref_theta_rad;  // unwrapped; empty for aps
  // Standard deviation of one reference position sample [m]: from the track's
  // metadata when it states one (sim.*), else estimated (see build).
  double ref_sigma_m = 0.0;
};

// Throws std::invalid_argument (one line naming the track and what is
// missing) when the track has no usable odometry or reference.
DiagInput build_diag_input(const Track& track);

}  // namespace odotune::diagnose

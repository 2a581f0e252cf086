// The odometry parameters an online calibrator estimates, the kinematics that
// turn wheel rates into body velocities with them, and one calibration sample
// (wheel rates + an external body-velocity measurement).
//
// Kinematics (../shared/specs/track-format.md; Fariña, Toledo & Acosta, "A New
// Approach to Real-Time Odometry Calibration Using an Adaptive Particle
// Filter Design", RA-L 2026, eq. 3 with the yaw rate divided by the wheel base
// as the papers' README notes):
//   V = (ω_r R_R + ω_l R_L) / 2,   W = (ω_r R_R − ω_l R_L) / D.
#pragma once

#include <cmath>
#include <string>

namespace odotune::filters {

struct OdometryParams {
  double wheel_radius_left_m = 0.0;   // R_L [m]
  double wheel_radius_right_m = 0.0;  // R_R [m]
  double wheel_base_m = 0.0;          // D [m]

  // True when every value is finite and > 0; otherwise *why (if not null)
  // names the first bad value ("wheel_base_m = -1 must be a finite number > 0").
  bool IsValid(std::string* why) const;
};

// The calibration of a body-velocity odometry (a twist the drive reports, or
// the commands): v = scale_v · v_in(t − delay_s), w = scale_w · w_in(t −
// delay_s). The identity by default.
struct TwistCorrection {
  double scale_v = 1.0;  // [-]
  double scale_w = 1.0;  // [-]
  double delay_s = 0.0;  // [s], ≥ 0: the motion lags its input by this much
  // Finite scales > 0 and a finite delay ≥ 0; *why names the first bad value.
  bool IsValid(std::string* why) const;
};

// A planar pose [m, m, rad] (theta unwrapped unless a caller says otherwise):
// ground-truth samples (odotune/objectives/pose_series.h) and poses integrated from
// body velocities (velocity_ukf.h's integrate_pose).
struct PlanarPose {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
};

struct BodyVelocity {
  double v_m_s = 0.0;    // V [m/s]
  double w_rad_s = 0.0;  // W [rad/s]
};

inline BodyVelocity body_velocity(const OdometryParams& p, double omega_l_rad_s, double omega_r_rad_s) {
  return {0.5 * (omega_r_rad_s * p.wheel_radius_right_m + omega_l_rad_s * p.wheel_radius_left_m),
          (omega_r_rad_s * p.wheel_radius_right_m - omega_l_rad_s * p.wheel_radius_left_m) / p.wheel_base_m};
}

// One iteration's input to a calibrator: the wheel rates at the instant of an
// external velocity measurement, and that measurement.
//
// Contract: dt_s ≥ 0 is the time since the previous sample (0 for the first);
// rates and measurement finite; variances > 0 (a caller without the sensor's
// variances uses its configured defaults).
struct CalibSample {
  double dt_s = 0.0;           // [s]
  double omega_l_rad_s = 0.0;  // ω_l [rad/s]
  double omega_r_rad_s = 0.0;  // ω_r [rad/s]
  double v_m_s = 0.0;          // V_m, external (e.g. lidar scan matching) [m/s]
  double w_rad_s = 0.0;        // W_m [rad/s]
  double v_var = 4e-4;         // var(V_m) [(m/s)²]
  double w_var = 4e-4;         // var(W_m) [(rad/s)²]
};

// What every calibrator reports after an iteration.
struct CalibEstimate {
  OdometryParams params;          // the estimate (PF: weighted mean, not the best particle)
  BodyVelocity velocity;          // V_O, W_O: the calibrated odometry's velocities now
                                  // (PF: weighted mean of the particles' V, W;
                                  // DKF: h(θ̂, ω) with the updated θ̂)
  double sd_radius_left_m = 0.0;  // spread of the estimate (PF: weighted sd; KF: √P)
  double sd_radius_right_m = 0.0;
  double sd_wheel_base_m = 0.0;
  int particles = 0;       // N after this iteration's resampling (0 for the Kalman filters)
  double n_eff = 0.0;      // N_eff before any resampling this iteration (PF)
  bool resampled = false;  // the PF resampled this iteration
};

}  // namespace odotune::filters

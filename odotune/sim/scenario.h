// A simulation scenario: everything the simulator needs to produce one track
// (robot, commanded motion, sensors, physics effects, slip episodes, seed). Plain data only;
// reading it from YAML is the CLI layer's job (odotune/formats/scenario_yaml.h),
// checking it is validate_scenario() in simulator.h, and the effect vocabulary
// (names, parameter ranges, command-line specs) is effects.h.
//
// Units are SI unless a name says otherwise (angle_deg, rate_deg_s, rate_hz).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <odotune/sim/model_terms.h>

namespace odotune::sim {

// The robot as built. The wheel controller and every tool reading the track
// believe these nominal values; effects (radius_error, ...) make the true
// world differ from them.
//
// Defaults: a small indoor differential-drive robot (about 0.4 m x 0.4 m,
// 10 kg, like a TurtleBot-class research base): 50 mm wheels on a 0.30 m
// track, 4096 counts per wheel revolution (a 1024-line quadrature encoder
// after the gearbox). The motor/body values feed only the power model
// (simulator.h) and are order-of-magnitude values for such a base: a 12 V
// gearmotor with a wheel-side torque constant of 0.5 N*m/A.
struct RobotParams {
  double wheel_radius_left_m = 0.05;   // nominal R_l [m]
  double wheel_radius_right_m = 0.05;  // nominal R_r [m]
  double wheel_base_m = 0.30;          // nominal D, between contact points [m]
  double ticks_per_rev = 4096;         // encoder counts per wheel revolution

  // Power model (see simulator.h, "Motor power").
  double mass_kg = 10.0;                  // body mass m [kg]
  double yaw_inertia_kg_m2 = 0.25;        // body yaw inertia I_z [kg*m^2] (m(a^2+b^2)/12 for 0.4x0.4 m)
  double wheel_inertia_kg_m2 = 1.2e-3;    // J_w: wheel + rotor reflected through the gearbox [kg*m^2]
  double viscous_friction_nm_s = 2e-3;    // b_v [N*m*s/rad], wheel side
  double coulomb_friction_nm = 0.05;      // tau_c [N*m], wheel side (bearings, gear, rolling)
  double coulomb_smoothing_rad_s = 0.5;   // omega_eps [rad/s] of tau_c*tanh(omega/omega_eps)
  double torque_constant_nm_per_a = 0.5;  // k_t [N*m/A], wheel side (motor k_t x gear ratio)
  double coil_resistance_ohm = 2.0;       // R_coil [ohm]
};

// One piece of commanded motion. Which fields matter depends on `kind`:
//   straight: distance_m (negative = reverse), speed_m_s (> 0)
//   arc:      radius_m (> 0), angle_deg (sign = turn direction, + = left), speed_m_s (> 0)
//   spin:     angle_deg (sign = turn direction), rate_deg_s (> 0)
//   stop:     duration_s (>= 0), the time spent at rest
// How segments become v_cmd(t), w_cmd(t) under the acceleration limits is
// documented in motion_profile.h.
struct Segment {
  enum class Kind { straight, arc, spin, stop };
  Kind kind = Kind::stop;
  double distance_m = 0.0;
  double speed_m_s = 0.0;
  double radius_m = 0.0;
  double angle_deg = 0.0;
  double rate_deg_s = 0.0;
  double duration_s = 0.0;
  int line = 0;  // line in the scenario file, for error messages (0 = unknown)
};

// One point of an explicit velocity profile: the commanded body velocities at
// time t_s. Between knots the command is linear in t (motion_profile.h).
struct VelocityKnot {
  double t_s = 0.0;      // [s]; the first knot at 0, strictly increasing
  double v_m_s = 0.0;    // v_cmd [m/s]
  double w_rad_s = 0.0;  // w_cmd [rad/s]
};

// The commanded motion: EITHER segments (planned under the acceleration
// limits) OR knots (an explicit profile, taken as given: the limits are not
// applied to it). Giving both is an error (motion_profile.h).
//
// The start pose is where the robot stands at t = 0, in the frame of the
// track's gt_*/aps_* columns (and of the slip_zone box): the ground truth's
// first row is exactly (start_x_m, start_y_m, start_theta_rad), theta
// unwrapped from there. It moves the world path rigidly and changes nothing
// the robot itself senses (ticks, commands, gyro, power, ext_velocity), except
// through slip_zone, whose box is fixed in that frame. Finite numbers;
// default: the origin, heading along +x.
struct MotionParams {
  double start_x_m = 0, start_y_m = 0, start_theta_rad = 0;  // initial pose [m, m, rad]
  double max_accel_m_s2 = 0.5;                               // |dv_cmd/dt| limit [m/s^2]
  double max_angular_accel_rad_s2 = 2.0;                     // |dw_cmd/dt| limit [rad/s^2]
  std::vector<Segment> segments;                             // flat; repeats already expanded
  std::vector<VelocityKnot> knots;                           // explicit profile (e.g. from a recorded track)
};

// Sensors. Every sensor samples at t = k / rate_hz (k = 0, 1, ...); a row of
// the track exists wherever at least one enabled sensor samples. Each period
// must be a whole number of integration steps. `resolution_*` rounds the
// reported value to that step (0 = full double precision); it is the sensor's
// LSB and keeps files small.
struct SensorParams {
  struct Encoders {  // ticks_l, ticks_r (+ omega_l, omega_r)
    bool enabled = true;
    double rate_hz = 100.0;
    bool omega = false;  // also write omega_l, omega_r [rad/s]
    double omega_resolution_rad_s = 1e-4;
  } encoders;
  struct Commands {  // v_cmd, w_cmd
    bool enabled = true;
    double rate_hz = 100.0;
    double resolution = 1e-4;  // [m/s] and [rad/s]
  } commands;
  struct Gyro {  // gyro_z
    bool enabled = true;
    double rate_hz = 100.0;
    double sigma_rad_s = 0.002;  // white noise std [rad/s]
    double resolution_rad_s = 1e-5;
  } gyro;
  struct Power {  // power_l, power_r
    bool enabled = true;
    double rate_hz = 100.0;
    double sigma_w = 0.02;  // white noise std [W]
    double resolution_w = 1e-3;
  } power;
  struct ExtVelocity {  // v_ext, w_ext, v_ext_var, w_ext_var
    bool enabled = true;
    double rate_hz = 10.0;
    double sigma_v_m_s = 0.02;    // white noise std of v_ext [m/s]
    double sigma_w_rad_s = 0.02;  // white noise std of w_ext [rad/s]
    double resolution = 1e-4;     // [m/s] and [rad/s]
  } ext_velocity;
  struct Aps {  // aps_x, aps_y
    bool enabled = true;
    double rate_hz = 1.0;
    double sigma_m = 0.06;  // white noise std per axis [m] (the study's 60 mm)
    double resolution_m = 1e-4;
  } aps;
  struct GroundTruth {  // gt_x, gt_y, gt_theta (theta unwrapped)
    bool enabled = true;
    double rate_hz = 100.0;
    double sigma_m = 0.0;    // optional white noise [m], default off
    double sigma_rad = 0.0;  // optional white noise [rad], default off
    double resolution_m = 1e-5;
    double resolution_rad = 1e-6;
  } ground_truth;
};

// The effects of ../shared/specs/physics-effects.md; an absent optional is an
// effect switched off. Field names are the spec's parameter names verbatim;
// the table of names, units and valid ranges is effects.h.
struct Effects {
  struct RadiusError {
    double scale_l = 1.0, scale_r = 1.0;
  };
  struct WheelBaseError {
    double scale = 1.0;
  };
  struct RadiusStep {
    double t = 0.0, scale_l = 1.0, scale_r = 1.0;
  };  // t [s]
  struct SpeedRadius {
    double c = 0.0;
  };  // [s^2/m^2]
  struct LateralSkid {
    double k = 0.0;
  };  // [s]
  struct LongitudinalSlip {
    double k = 0.0;
  };  // [s^2/m]
  struct SlipZone {
    double x0 = 0, x1 = 0, y0 = 0, y1 = 0, s_l = 0, s_r = 0;
  };  // [m], [-]
  struct GyroBias {
    double b = 0.0;
  };  // [rad/s]
  struct GyroScale {
    double s = 1.0;
  };
  struct ActuatorLag {
    double tau = 0.0;
  };  // [s]
  struct TimeOffset {
    double dt = 0.0;
  };  // [s]
  struct OdometryBias {
    double b_v = 0.0, b_w = 0.0;
  };  // [m/s], [rad/s]

  std::optional<RadiusError> radius_error;
  std::optional<WheelBaseError> wheel_base_error;
  std::optional<RadiusStep> radius_step;
  std::optional<SpeedRadius> speed_radius;
  std::optional<LateralSkid> lateral_skid;
  std::optional<LongitudinalSlip> longitudinal_slip;
  std::optional<SlipZone> slip_zone;
  std::optional<GyroBias> gyro_bias;
  std::optional<GyroScale> gyro_scale;
  std::optional<ActuatorLag> actuator_lag;
  std::optional<TimeOffset> time_offset;
  std::optional<OdometryBias> odometry_bias;
};

// A slip episode: a transient, timed loss of the rolling contact of ONE
// wheel (Farina et al., Sensors 2023, 23, 961, §3.2/§4.1/§5: "other wheels
// with greater wear to generate slipping ... applying pressure on one side,
// preventing the rotation of a wheel while allowing the other to turn
// freely"), during which that wheel's motor power and encoder rate
// decorrelate. Not one of the spec's effects (physics-effects.md is left as
// it is): a list of its own (Scenario::slip_episodes), written to a track as
// sim.slip_episodes; formatting, parsing, validation and the strength
// profile are slip_episodes.h, the physics simulator.h ("Slip episodes").
//
// Strength: 0 before t0_s, rising linearly to `s` over [t0_s, t0_s + ramp_s],
// `s` until t1_s - ramp_s, falling linearly to 0 at t1_s.
// Valid: t0_s >= 0, t1_s > t0_s, 0 < s <= 0.9, ramp_s > 0 with 2*ramp_s <=
// t1_s - t0_s, brake_nm >= 0 (hold) or 0 (spin); episodes on the same wheel
// must not overlap in time (they may touch: t1_s of one = t0_s of the next).
struct SlipEpisode {
  enum class Kind {
    spin,  // a worn wheel losing grip: turns as commanded, the ground moves less
    hold,  // a wheel held back: turns slower, its contact is dragged along
  };
  enum class Wheel { left, right };
  Kind kind = Kind::spin;
  Wheel wheel = Wheel::left;
  double t0_s = 0.0;      // start [s] (simulation time)
  double t1_s = 0.0;      // end [s]
  double s = 0.0;         // peak strength [-]: the lost fraction of ground speed (spin) or rotation (hold)
  double ramp_s = 0.2;    // duration of each linear ramp [s]
  double brake_nm = 0.0;  // hold: braking torque at full strength [N*m]; 0 = 2*robot.coulomb_friction_nm
  int line = 0;           // line in the scenario file, for error messages (0 = unknown)
};

struct Scenario {
  std::string name = "simulated";  // track name (metadata `name`)
  std::string source;              // scenario file name, written as sim.scenario ("" = none)
  std::uint64_t seed = 1;          // all noise derives from it
  double step_s = 0.001;           // integration step [s]; 1/step_s must be a whole number
  RobotParams robot;
  MotionParams motion;
  SensorParams sensors;
  Effects effects;
  std::vector<SlipEpisode> slip_episodes;  // transient slips, any order (see SlipEpisode)
  std::vector<ModelTerm> terms;            // ground-speed corrections outside the effects (model_terms.h)
};

}  // namespace odotune::sim

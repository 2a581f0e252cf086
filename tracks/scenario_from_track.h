// A simulator scenario that re-drives a track: the robot of the track, its
// sensors at their rates, a given set of physics effects (e.g. the ones a
// diagnosis fitted), and as motion the explicit velocity knots (scenario.h,
// motion_profile.h) that make the simulated robot, WITH those effects, drive
// the track's reference path. Simulating it gives the corrected robot model
// on the same drive as the recording (sim-to-real comparison; a simulated
// track the tuner can use).
//
// Reference path: the ground truth gt_x, gt_y (+ gt_theta when present) if
// the track has it, else the position fixes aps_x, aps_y.
//
// Knots: at t_k = k / knot_rate_hz (k = 0, 1, ...) over the reference's time
// span, plus one knot at its end; time is shifted so the reference's first
// sample is t = 0 (simulated time = track time - first reference time).
// Smoothing filter: at each knot, a local CUBIC least-squares fit in time
// (Savitzky-Golay-like) of x, y (and unwrapped theta) to the reference
// samples within +-half_window_s of t_k (+-fixes_half_window_s for position
// fixes), the window widened nearest-first to min_fit_points samples when it
// holds fewer; one-sided at the ends. The fitted derivative is exact for
// cubic motion and averages white reference noise over the window; a
// quadratic fit's derivative would be biased on arcs by about -(w*h)^2/10
// (0.6 % of v at w = 0.5 rad/s, h = 0.5 s), which the cubic removes. From the
// fit at t_k:
//   with gt_theta: theta and w = theta' from its fit;
//   without (position fixes, or ground truth without gt_theta): theta = the
//     direction of the fitted velocity atan2(y', x') (forward driving
//     assumed), trusted only where the speed exceeds min_speed_m_s and 3
//     standard errors of the fitted velocity (from the fit residuals), held
//     from the previous knot elsewhere (before the first trusted one: that
//     one's); w = central differences of this heading over the knots (0 next
//     to an untrusted heading). A spin in place or reverse driving is
//     invisible to positions alone and is lost.
//   v = x' cos(theta) + y' sin(theta)  (the forward body speed; a sideways
//     slide, e.g. lateral_skid, is left to the simulator to recreate).
//
// Commands from the reference body velocities (v, w), inverting the effects
// that change what the wheels do to the ground (simulator.h's world model), so
// the simulated GROUND path follows the reference while the encoders see what
// the corrected robot would count:
//   ground speeds g_r,l = v +- w*D_true/2 (D_true = D*wheel_base_error.scale);
//   slip_zone: g /= (1 - s) while the fitted reference position is inside
//     the box (the box in the recording's frame, see below);
//   longitudinal_slip (approximate): rim speed u = g / (1 - min(0.5, k*|dg/dt|)),
//     dg/dt by central differences over the knots;
//   speed_radius: u = z*(1 + c*z^2) solved for z = R_true*omega (Newton);
//   radius_error, radius_step: omega = z / R_true(t_k);
//   actuator_lag (approximate): omega_ref = omega + tau*d(omega)/dt, central
//     differences over the knots (a first-order lead, the inverse of the lag);
//   then v_cmd, w_cmd = the nominal forward kinematics of omega_ref (which is
//   what the simulator's wheel controller inverts).
// lateral_skid, gyro_bias, gyro_scale, time_offset and odometry_bias need no
// inversion (they do not change v, w or only change sensor readings). Without
// effects the knots are the reference's (v, w).
//
// Frames: the scenario's start pose (MotionParams::start_*) is the
// reference's first pose, fitted at the first knot: x, y from the fit; theta
// from gt_theta's fit when the reference has it, else from the path direction:
// the start heading th0 with which the knots' turning (th0 + integral of w)
// agrees best with the trusted directions of travel (their circular mean,
// weighted by speed): about the first trusted direction when the directions
// are trusted throughout, but not thrown off by a direction "trusted" while
// the robot stands (e.g. a settling fix) nor by a turn lost in an untrusted
// stretch. The simulated track therefore lies in the recording's frame: its
// gt_x, gt_y, gt_theta (theta continuing the recording's unwrapped gt_theta)
// are comparable with the recording's reference without any alignment, up to
// the smoothing and, for position fixes, the error of the estimated start
// pose. Effect parameters are taken in the recording's frame too: slip_zone's
// box in its map coordinates (as a diagnosis fits it), radius_step.t in its
// clock (shifted by the first reference time like the knots).
//
// Name "<track name>-corrected"; seed and step_s from the options; source ""
// (the YAML reader sets it from the file name).
// Robot: wheel radii, wheel base, ticks_per_rev from the track metadata
// (scenario.h defaults where absent); the power-model fields and the
// acceleration limits from the track's sim.robot.* / sim.max_* metadata when
// present (a simulated track), else scenario.h defaults.
// Sensors: each column group the track has (encoders: ticks or omega, omega
// columns -> encoders.omega; commands: v_cmd/w_cmd; gyro; power; ext_velocity;
// aps) is enabled at the rate 1 / (median period of the rows holding a sample
// of the group), the period rounded to a whole number of step_s (the
// simulator's requirement); a group with fewer than 2 samples gets its
// scenario.h default rate. Groups the track lacks are disabled. ground_truth
// is always enabled, at the gt columns' rate or, without them, at the highest
// rate of the enabled groups. Noise sigmas from the track's sim.* metadata
// (sim.gyro_sigma_rad_s, sim.power_sigma_w, sim.ext_sigma_v_m_s,
// sim.ext_sigma_w_rad_s, sim.aps_sigma_m, sim.gt_sigma_m, sim.gt_sigma_rad)
// when present and a finite number >= 0; for ext_velocity else sqrt(median
// v_ext_var / w_ext_var) when those columns exist; else scenario.h defaults.
// Resolutions: scenario.h defaults.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tracks/scenario.h"
#include "tracks/track.h"

namespace odotune::sim {

struct ScenarioFromTrackOptions {
  std::uint64_t seed = 1;            // the scenario's noise seed
  double knot_rate_hz = 10.0;        // knots per second, in (0, 1000]
  double half_window_s = 0.5;        // smoothing half-width [s], > 0
  double fixes_half_window_s = 2.0;  // the same for a position-fix reference [s]
  std::size_t min_fit_points = 6;    // at least this many samples per local fit, >= 4
  double min_speed_m_s = 0.02;       // heading-from-path speed threshold [m/s], >= 0
  double step_s = 0.001;             // the scenario's integration step [s]

  bool IsValid(std::string* why) const;
};

// The scenario described in the file comment. `effect_specs` are in the
// simulator's command-line form ("lateral_skid:k=0.021", effects.h), applied
// in order. Throws std::invalid_argument: a bad spec (the message contains the
// spec), a track without a reference path, with fewer than 3 reference
// samples or longer than the simulator accepts (naming the track), invalid
// options, or a scenario the simulator would reject (validate_scenario's
// message).
Scenario scenario_from_track(const Track& track, const std::vector<std::string>& effect_specs,
                             const ScenarioFromTrackOptions& options = {});

}  // namespace odotune::sim

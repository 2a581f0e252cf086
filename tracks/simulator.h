// The differential-drive robot simulator: Scenario (scenario.h) -> Track.
//
// Deterministic: the same scenario and seed give a bit-identical Track (and so
// a byte-identical file) on the same build. All noise comes from
// std::mt19937_64 (whose output the C++ standard fixes) through our own
// Box-Muller transform, because std::normal_distribution is
// implementation-defined and differs between standard libraries. Each sensor
// has its own stream (seeded from the scenario seed with SplitMix64), so
// switching one sensor or effect on or off never changes another sensor's noise.
//
// World model, integrated with a fixed step h = Scenario::step_s (1 ms):
//
//  1. Commands: v_cmd(t), w_cmd(t) from the segments (motion_profile.h).
//  2. Wheel controller: the controller believes the NOMINAL robot; its wheel
//     rate references are the inverse kinematics of track-format.md with the
//     nominal radii R_l, R_r and base D:
//         omega_ref_l = (v_cmd - w_cmd*D/2)/R_l,  omega_ref_r = (v_cmd + w_cmd*D/2)/R_r.
//     The wheels follow the references ideally, or with effect actuator_lag
//     through d(omega)/dt = (omega_ref - omega)/tau, discretised exactly for
//     a reference linear over the step (first-order hold). As the kinematics
//     are linear in the wheel rates, the true body velocities then follow
//     v_cmd, w_cmd through the same lag (physics-effects.md).
//  3. True wheel radii: R_true = R_nom * radius_error.scale * (radius_step.scale
//     from radius_step.t on); with speed_radius the effective radius is
//     R_true*(1 + c*u^2), u = R_true*omega. Rim speed u_rim = R_eff*omega.
//  4. Ground speed of each wheel over a step: mean rim speed * (1 - s_long) *
//     (1 - s_zone), where s_long = min(0.5, k*|du_rim/dt|) (longitudinal_slip)
//     and s_zone = slip_zone.s_l / s_r while the pose at the start of the step
//     is inside the box. (Both slips multiply when both are on, and with a
//     spin episode's 1 - s, below.)
//  5. Body: v = (g_r + g_l)/2, w = (g_r - g_l)/D_true with D_true =
//     D*wheel_base_error.scale; lateral_skid adds v_y = -k*v*w (body frame,
//     +y = left). The pose integrates exactly for velocities constant over the
//     step (arc update with sinc), using the step means of the wheel rates:
//     second order in h, like RK2.
//  5a. Model terms (Scenario::terms, model_terms.h; none by default): before
//     step 5, each wheel's ground speed g gets sum coef*basis(state) added,
//     the state taken at the step's middle: g_l, g_r as step 4 gives them,
//     rim accelerations (u1 - u0)/h, v, w from g_l, g_r (D_true), the
//     rotation angles phi of step 6 averaged over the step's ends, the pose
//     at the step's start, t = the step's middle. Written to the track as
//     sim.terms. An out-of-round left wheel, radius ±1 % once per turn:
//     the term v_l*sin(phi_l) with coef 0.01.
//  6. Wheel rotation angle phi integrates omega (trapezoid; exact for omega
//     linear over the step). Encoders count the ROTATION, so slip and radius
//     errors never change the ticks: ticks = floor(phi/(2 pi)*ticks_per_rev)
//     (odometry_bias, below, offsets what they report).
//
// Sensors (rows at the union of the sample instants k/rate_hz):
//  * ticks_l/r (+ omega_l/r), v_cmd, w_cmd: the odometry columns. With effect
//    time_offset the row stamped t holds what was measured at t - dt (linear
//    interpolation of the internal 1 ms states; the first value is held
//    before t = 0 and the last after the end).
//    With effect odometry_bias the odometry's body velocities read v + b_v,
//    w + b_w (physics-effects.md): v_cmd, w_cmd get b_v, b_w added; for the
//    wheels the offset is on the body velocities they imply through the
//    odometry's own NOMINAL model (radii R_l, R_r, base D, track-format.md),
//    i.e. constant wheel-rate offsets
//        bias_l = (b_v - b_w*D/2)/R_l,  bias_r = (b_v + b_w*D/2)/R_r,
//    added to omega_l/r, and bias*t_m added to the counted rotation phi
//    before the ticks are taken (t_m the measurement time: t - dt, clamped to
//    the run like the odometry itself). So the nominal kinematics of the
//    recorded wheels give the wheels' own reading + (b_v, b_w), and a robot at
//    rest counts ticks: its odometry drifts by b_v*t, its heading by b_w*t.
//    Ground truth, gyro, power, ext_velocity and fixes are unaffected.
//  * gyro_z = gyro_scale.s * w + gyro_bias.b + N(0, sigma^2).
//  * v_ext, w_ext = true body v, w + N(0, sigma^2); v_ext_var, w_ext_var = sigma^2.
//  * aps_x, aps_y = true position + N(0, sigma^2) per axis.
//  * gt_x, gt_y, gt_theta (unwrapped) = true pose (+ optional noise, default off).
//  * power_l, power_r: motor power (below) + N(0, sigma^2).
//  Every value is then rounded to its sensor's resolution (scenario.h).
//
// Motor power, per wheel (standard brushed/permanent-magnet DC motor model,
// quantities referred to the wheel side of the gearbox):
//    tau = J_w*domega/dt + b_v*omega + tau_c*tanh(omega/omega_eps)
//          + (m*a/2 -+ I_z*alpha/D_true) * R_eff        (- left, + right)
//    P   = tau*omega + (tau/k_t)^2 * R_coil             [W]
// i.e. wheel + rotor inertia, viscous and (smoothed) Coulomb friction, and each
// wheel's share of accelerating the body (mass m, linear acceleration a) and
// of turning it (yaw inertia I_z, angular acceleration alpha), then mechanical
// power plus copper loss (current i = tau/k_t). P < 0 is regenerative braking.
// a and alpha are the true body accelerations, so under slip power and wheel
// speed decorrelate (the relation Farina et al., Sensors 2023, 23, 961 use to
// detect slip: ../shared/papers/002_*.txt).
//
// Slip episodes (Scenario::slip_episodes, scenario.h; strength s(t) of the
// episode acting on a wheel, ramped, 0 outside episodes). Transient losses of
// one wheel's rolling contact, modelled on the slips Farina et al. (Sensors
// 2023, 23, 961, §3.2, §5) provoked on their robot to train an LSTM slip
// detector on motor power + encoder increments: worn wheels that slip, and
// "applying pressure on one side, preventing the rotation of a wheel while
// allowing the other to turn freely". In both, power and wheel speed
// decorrelate, which the kinematic model and the nominal power both miss.
//  * spin (a worn wheel losing grip): the wheel turns as the controller
//    commands (omega = omega_ctrl, so the encoders count as usual) but its
//    ground speed is multiplied by 1 - s (step 4; s averaged over the step's
//    ends), and the contact transmits only the fraction 1 - s of the force:
//    in the motor model the Coulomb/rolling term and the body-load term are
//    both multiplied by (1 - s). Power drops, wheel speed does not.
//  * hold (a wheel held back, e.g. pressed on by a hand or an obstacle): the
//    wheel's rotation is slowed to omega = (1 - s)*omega_ctrl (omega_ctrl =
//    what the controller / actuator_lag gives; the controller's own state is
//    unchanged, as if it did not know), and the encoders count the slowed
//    rotation (step 6), while the contact is dragged along at the ground
//    speed of the unbraked wheel (R_eff(omega_ctrl)*omega_ctrl, with the
//    other slips as usual): the encoders under-read the motion and the true
//    path is that of the run without the episode. The motor model uses the
//    slowed rotation's rate and derivative and adds a braking torque
//        tau_brake = brake_nm * (s(t)/s) * tanh(omega_ctrl/omega_eps)
//    (ramping with the episode; the smoothed sign of the Coulomb term, so it
//    vanishes at standstill). brake_nm = 0 in the scenario means 2*tau_c (the
//    wheel's own Coulomb torque: a firm hand on the tyre). Power rises when
//    (tau + tau_brake)*(1 - s) exceeds tau, i.e. for a brake that is large
//    against the wheel's load at strong s (a hold at s = 0.8 needs
//    tau_brake > 4*tau); with a weaker brake power falls with the speed.
// Outside episodes every operation is the one without episodes, so a track is
// bit-identical to the run without them up to the first episode (and, for
// spin, its ticks throughout). Several episodes may act at once only on
// different wheels (validate_scenario). Where the episodes were is written to
// the track as sim.slip_episodes (slip_episodes.h).
//
// Sources: kinematics and every effect model: ../shared/specs/track-format.md
// and physics-effects.md (taken literally, with their units); motor model: the
// textbook DC-motor equations (torque = k_t*i, copper loss i^2*R; e.g. Hughes
// & Drury, "Electric Motors and Drives"); noise: Box & Muller (1958), SplitMix64
// (Steele, Lea & Flood 2014); sensor defaults (1 Hz position fixes, sigma
// 60 mm): Kovacs et al., ../shared/papers/001_*.txt.
#pragma once

#include <string>

#include "tracks/scenario.h"
#include "tracks/track.h"

namespace odotune::sim {

// Checks every field (ranges, sample periods being whole numbers of steps, the
// motion profile, a bound on the size of the result). On failure `why` is one
// line naming the field, its value and what was expected.
bool validate_scenario(const Scenario& scenario, std::string* why);

// Runs the simulation. Throws std::invalid_argument with validate_scenario's
// message for an invalid scenario.
Track simulate(const Scenario& scenario);

// Upper bounds enforced by validate_scenario (no unbounded allocation).
inline constexpr double kMaxSimSteps = 2e8;
inline constexpr double kMaxSimRows = 1e7;

}  // namespace odotune::sim

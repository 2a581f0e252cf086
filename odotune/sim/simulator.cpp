#include <odotune/sim/normal_rng.h>
#include <odotune/sim/simulator.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include <odotune/core/planar_motion.h>
#include <odotune/core/why.h>

#include <odotune/sim/effects.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/slip_episodes.h>

namespace odotune::sim {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

enum Stream : std::uint64_t { kGyroStream = 1, kPowerStream, kExtStream, kApsStream, kGtStream };

Normal make_stream(std::uint64_t seed, Stream s) {
  return Normal(splitmix64(seed ^ splitmix64(static_cast<std::uint64_t>(s))));
}

// Rounds x to a multiple of `res` (res = 0: unchanged). For res = 10^-n the
// result is the double nearest to the decimal, so it prints short.
double quantise(double x, double res) {
  if (!(res > 0.0)) return x;
  const double inv = 1.0 / res;
  const double inv_round = std::round(inv);
  if (inv_round >= 1.0 && std::abs(inv - inv_round) <= 1e-9 * inv_round)
    return std::round(x * inv_round) / inv_round;
  return std::round(x / res) * res;
}

// 1/step_s as a whole number, or 0 if it is not one.
std::int64_t steps_per_second(double step_s) {
  if (!(std::isfinite(step_s) && step_s > 0.0 && step_s <= 0.1)) return 0;
  const double inv = 1.0 / step_s;
  const double r = std::round(inv);
  if (r > 1e7 || std::abs(inv - r) > 1e-9 * r) return 0;
  return static_cast<std::int64_t>(r);
}

// Sample period in steps, or 0 if it is not a whole number.
std::int64_t period_steps(double rate_hz, std::int64_t sps) {
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0)) return 0;
  const double p = static_cast<double>(sps) / rate_hz;
  const double r = std::round(p);
  if (r < 1.0 || std::abs(p - r) > 1e-9 * r) return 0;
  return static_cast<std::int64_t>(r);
}

struct SensorView {
  const char* name;
  bool enabled;
  double rate_hz;
};

std::array<SensorView, 7> sensor_views(const SensorParams& s) {
  return {{{"encoders", s.encoders.enabled, s.encoders.rate_hz},
           {"commands", s.commands.enabled, s.commands.rate_hz},
           {"gyro", s.gyro.enabled, s.gyro.rate_hz},
           {"power", s.power.enabled, s.power.rate_hz},
           {"ext_velocity", s.ext_velocity.enabled, s.ext_velocity.rate_hz},
           {"aps", s.aps.enabled, s.aps.rate_hz},
           {"ground_truth", s.ground_truth.enabled, s.ground_truth.rate_hz}}};
}
enum SensorIndex { kEnc, kCmd, kGyro, kPower, kExt, kAps, kGt };

// Variance as written to v_ext_var/w_ext_var: sigma^2 to 12 significant digits
// (so 0.02 gives 0.0004, not 0.00040000000000000002).
double tidy_variance(double sigma) {
  const std::string s = fmt::format("{:.12g}", sigma * sigma);
  return std::stod(s);
}

// Wheel-level state at one instant: the ROTATION the encoders count (slowed
// by a hold episode, else the controller's rate).
struct WheelState {
  double phi_l = 0, phi_r = 0;  // rotation angle [rad]
  double om_l = 0, om_r = 0;    // rate [rad/s]
};

// What the slip episodes do to one wheel at one instant (simulator.h, "Slip
// episodes"); all zero outside episodes.
struct WheelSlip {
  double spin = 0.0;      // spin strength: lost fraction of ground speed and contact force
  double hold = 0.0;      // hold strength: lost fraction of the rotation
  double brake_nm = 0.0;  // hold's braking torque now [N*m] (ramps with the strength)
};

// True state recorded at a row.
struct Truth {
  double x = 0, y = 0, theta = 0;  // pose [m, m, rad]
  double v = 0, w = 0;             // body velocities, mean over the last step [m/s, rad/s]
  double p_l = 0, p_r = 0;         // motor power [W]
};

bool positive(double v) { return std::isfinite(v) && v > 0.0; }
bool nonneg(double v) { return std::isfinite(v) && v >= 0.0; }

bool check_robot(const RobotParams& r, std::string* why) {
  const std::array<std::pair<const char*, double>, 4> pos = {
      {{"wheel_radius_left_m", r.wheel_radius_left_m},
       {"wheel_radius_right_m", r.wheel_radius_right_m},
       {"wheel_base_m", r.wheel_base_m},
       {"coulomb_smoothing_rad_s", r.coulomb_smoothing_rad_s}}};
  for (const auto& [name, v] : pos)
    if (!positive(v)) return core::invalid(why, fmt::format("robot.{} = {}; expected a number > 0", name, v));
  if (!(std::isfinite(r.ticks_per_rev) && r.ticks_per_rev >= 1.0 && r.ticks_per_rev <= 1e9))
    return core::invalid(why, fmt::format("robot.ticks_per_rev = {}; expected a number in [1, 1e9]",
                                          r.ticks_per_rev));
  if (!positive(r.torque_constant_nm_per_a))
    return core::invalid(why, fmt::format("robot.torque_constant_nm_per_a = {}; expected a number > 0",
                                          r.torque_constant_nm_per_a));
  const std::array<std::pair<const char*, double>, 6> nn = {{{"mass_kg", r.mass_kg},
                                                             {"yaw_inertia_kg_m2", r.yaw_inertia_kg_m2},
                                                             {"wheel_inertia_kg_m2", r.wheel_inertia_kg_m2},
                                                             {"viscous_friction_nm_s", r.viscous_friction_nm_s},
                                                             {"coulomb_friction_nm", r.coulomb_friction_nm},
                                                             {"coil_resistance_ohm", r.coil_resistance_ohm}}};
  for (const auto& [name, v] : nn)
    if (!nonneg(v)) return core::invalid(why, fmt::format("robot.{} = {}; expected a number >= 0", name, v));
  return true;
}

bool check_sensors(const SensorParams& s, double step_s, std::int64_t sps, std::string* why) {
  for (const SensorView& v : sensor_views(s)) {
    if (!v.enabled) continue;
    if (!positive(v.rate_hz))
      return core::invalid(why,
                           fmt::format("sensors.{}.rate_hz = {}; expected a number > 0", v.name, v.rate_hz));
    if (period_steps(v.rate_hz, sps) == 0)
      return core::invalid(why, fmt::format("sensors.{}.rate_hz = {}: its period is not a whole number of "
                                            "{} s integration steps; expected a rate that divides {} Hz",
                                            v.name, v.rate_hz, step_s, sps));
  }
  if (!s.encoders.enabled && !s.commands.enabled)
    return core::invalid(why, "sensors: neither encoders nor commands is enabled; a track needs an odometry "
                              "source (expected sensors.encoders or sensors.commands enabled)");
  const std::array<std::pair<const char*, double>, 15> nn2 = {
      {{"encoders.omega_resolution_rad_s", s.encoders.omega_resolution_rad_s},
       {"commands.resolution", s.commands.resolution},
       {"gyro.sigma_rad_s", s.gyro.sigma_rad_s},
       {"gyro.resolution_rad_s", s.gyro.resolution_rad_s},
       {"power.sigma_w", s.power.sigma_w},
       {"power.resolution_w", s.power.resolution_w},
       {"ext_velocity.sigma_v_m_s", s.ext_velocity.sigma_v_m_s},
       {"ext_velocity.sigma_w_rad_s", s.ext_velocity.sigma_w_rad_s},
       {"ext_velocity.resolution", s.ext_velocity.resolution},
       {"aps.sigma_m", s.aps.sigma_m},
       {"aps.resolution_m", s.aps.resolution_m},
       {"ground_truth.sigma_m", s.ground_truth.sigma_m},
       {"ground_truth.sigma_rad", s.ground_truth.sigma_rad},
       {"ground_truth.resolution_m", s.ground_truth.resolution_m},
       {"ground_truth.resolution_rad", s.ground_truth.resolution_rad}}};
  for (const auto& [name, v] : nn2)
    if (!nonneg(v)) return core::invalid(why, fmt::format("sensors.{} = {}; expected a number >= 0", name, v));
  return true;
}

// The motion profile, the episodes' starts within it and speed_radius's
// shrink at its fastest rim speed; sets *duration [s].
bool check_motion(const Scenario& sc, double* duration_s, std::string* why) {
  double duration = 0.0;
  double max_rim_m_s = 0.0;  // fastest nominal rim speed |v| + |w|*D/2
  try {
    const MotionProfile profile(sc.motion);
    duration = profile.duration_s();
    for (const auto& k : profile.knots())
      max_rim_m_s = std::max(max_rim_m_s, std::abs(k.v_m_s) + std::abs(k.w_rad_s) * sc.robot.wheel_base_m / 2);
  } catch (const ProfileError& e) {
    return core::invalid(why, fmt::format("motion: {}", e.what()));
  }
  for (std::size_t i = 0; i < sc.slip_episodes.size(); ++i)
    if (!(sc.slip_episodes[i].t0_s < duration))
      return core::invalid(
          why, fmt::format("slip_episodes[{}]: t0_s = {} is not before the end of the motion at {} s; "
                           "expected an episode that starts during the drive",
                           i + 1, sc.slip_episodes[i].t0_s, duration));
  if (sc.effects.speed_radius) {
    // Radius scales are at most 1.5 each (effects.h), so u < 2.25 * max_rim.
    const double u = 2.25 * max_rim_m_s, c = sc.effects.speed_radius->c;
    if (1.0 + c * u * u < 0.5)
      return core::invalid(why, fmt::format("effects: speed_radius.c = {} would shrink the effective radius "
                                            "R*(1 + c*u^2) below R/2 at rim speeds up to {:.3g} m/s; expected "
                                            "c > {:.3g}",
                                            c, u, -0.5 / (u * u)));
  }
  *duration_s = duration;
  return true;
}

// The run's size: its integration steps and its rows.
bool check_size(const Scenario& sc, std::int64_t sps, double duration, std::string* why) {
  const double steps = std::ceil(duration * static_cast<double>(sps) - 1e-6);
  if (steps > kMaxSimSteps)
    return core::invalid(why, fmt::format("motion lasts {:.3g} s = {:.3g} steps; expected at most {:.3g} steps "
                                          "(shorten the motion or enlarge step_s)",
                                          duration, steps, kMaxSimSteps));
  double rows = 0.0;
  for (const SensorView& v : sensor_views(sc.sensors))
    if (v.enabled) rows += duration * v.rate_hz + 1.0;
  if (rows > kMaxSimRows)
    return core::invalid(why, fmt::format("the track would have about {:.3g} rows; expected at most {:.3g} "
                                          "(lower the sensor rates or shorten the motion)",
                                          rows, kMaxSimRows));
  return true;
}

// The rows: the union of the sensor sample instants, on the grid of the
// periods' greatest common divisor.
struct RowGrid {
  std::array<std::int64_t, 7> period{};  // sample period per sensor [steps] (0: off)
  std::int64_t n_steps = 0;              // integration steps of the run
  std::vector<std::int64_t> row_k;       // step index of each row
  bool sampled(std::size_t r, SensorIndex s) const { return period[s] > 0 && row_k[r] % period[s] == 0; }
};

RowGrid row_grid(const SensorParams& sensors, const MotionProfile& profile, std::int64_t sps) {
  const double spsd = static_cast<double>(sps);
  RowGrid grid;
  auto& period = grid.period;
  const auto views = sensor_views(sensors);
  std::int64_t g = 0, l = 1;
  for (std::size_t i = 0; i < views.size(); ++i) {
    period[i] = views[i].enabled ? period_steps(views[i].rate_hz, sps) : 0;
    if (period[i] > 0) g = std::gcd(g, period[i]);
    if (period[i] > 0 && l <= 10 * sps) l = std::lcm(l, period[i]);
  }
  // The robot stays at rest after the motion until an instant where every
  // sensor samples (at most 10 s; else the next row instant), so the last row
  // is complete and shows the final pose.
  const std::int64_t end_multiple = l <= 10 * sps ? l : g;
  auto n_steps = static_cast<std::int64_t>(std::max(0.0, std::ceil(profile.duration_s() * spsd - 1e-6)));
  n_steps = (n_steps + end_multiple - 1) / end_multiple * end_multiple;
  for (std::int64_t k = 0; k <= n_steps; k += g)
    for (std::int64_t p : period)
      if (p > 0 && k % p == 0) {
        grid.row_k.push_back(k);
        break;
      }
  grid.n_steps = n_steps;
  return grid;
}

// Odometry query positions (fractional step index of t - dt), clamped.
std::vector<double> odometry_queries(const RowGrid& grid, const Effects& fx, double spsd) {
  const double dt_odo = fx.time_offset ? fx.time_offset->dt : 0.0;
  const std::size_t n_rows = grid.row_k.size();
  std::vector<double> q(n_rows);
  for (std::size_t r = 0; r < n_rows; ++r) {
    double f = static_cast<double>(grid.row_k[r]) - dt_odo * spsd;
    if (std::abs(f - std::round(f)) < 1e-6) f = std::round(f);
    q[r] = std::clamp(f, 0.0, static_cast<double>(grid.n_steps));
  }
  return q;
}

// The robot and the effects as the physics step uses them.
struct Physics {
  const RobotParams& rb;
  const Effects& fx;
  double h;  // step [s]
  double R_l, R_r, D, D_true;
  double c_sr, k_skid, k_slip, tau;
  // First-order-hold discretisation of d(om)/dt = (ref - om)/tau over one step:
  // om1 = e*om0 + (1-e)*ref0 + (ref1-ref0)*(1 - tau*(1-e)/h), e = exp(-h/tau).
  double one_minus_e, lag_e, lag_ramp;
  SlipSchedule slips;

  Physics(const Scenario& sc, double step_h)
      : rb(sc.robot),
        fx(sc.effects),
        h(step_h),
        R_l(rb.wheel_radius_left_m),
        R_r(rb.wheel_radius_right_m),
        D(rb.wheel_base_m),
        D_true(D * (fx.wheel_base_error ? fx.wheel_base_error->scale : 1.0)),
        c_sr(fx.speed_radius ? fx.speed_radius->c : 0.0),
        k_skid(fx.lateral_skid ? fx.lateral_skid->k : 0.0),
        k_slip(fx.longitudinal_slip ? fx.longitudinal_slip->k : 0.0),
        tau(fx.actuator_lag ? fx.actuator_lag->tau : 0.0),
        one_minus_e(tau > 0.0 ? -std::expm1(-h / tau) : 1.0),
        lag_e(1.0 - one_minus_e),
        lag_ramp(tau > 0.0 ? 1.0 - tau * one_minus_e / h : 1.0),
        slips(sc.slip_episodes) {}

  double base_radius(double t, bool right) const {  // R_nom * scales [m]
    double R = right ? R_r : R_l;
    if (fx.radius_error) R *= right ? fx.radius_error->scale_r : fx.radius_error->scale_l;
    if (fx.radius_step && t >= fx.radius_step->t)
      R *= right ? fx.radius_step->scale_r : fx.radius_step->scale_l;
    return R;
  }
  double eff_radius(double om, double R) const {  // speed_radius: R*(1 + c*u^2), u = R*om
    const double u = R * om;
    return R * (1.0 + c_sr * u * u);
  }
  bool in_zone(double x, double y) const {
    const auto& z = fx.slip_zone;
    return z && x >= z->x0 && x <= z->x1 && y >= z->y0 && y <= z->y1;
  }
  WheelSlip wheel_slip(double t, SlipEpisode::Wheel wheel) const {
    WheelSlip ws;
    const SlipSchedule::Active a = slips.at(t, wheel);
    if (!a.episode) return ws;
    if (a.episode->kind == SlipEpisode::Kind::spin) {
      ws.spin = a.strength;
    } else {
      ws.hold = a.strength;
      const double full = a.episode->brake_nm > 0.0 ? a.episode->brake_nm : 2.0 * rb.coulomb_friction_nm;
      ws.brake_nm = full * a.strength / a.episode->s;
    }
    return ws;
  }
  // om, dom: the wheel's rotation rate and its derivative; om_ctrl: the
  // controller's rate (the braking torque's sign). Outside episodes grip = 1
  // and brake_nm = 0, which leave every floating-point operation unchanged.
  double motor_power(double om, double dom, double load_force, double R_eff, const WheelSlip& ws,
                     double om_ctrl) const {
    const double grip = 1.0 - ws.spin;
    double torque = rb.wheel_inertia_kg_m2 * dom + rb.viscous_friction_nm_s * om +
                    rb.coulomb_friction_nm * std::tanh(om / rb.coulomb_smoothing_rad_s) * grip +
                    load_force * R_eff * grip;
    if (ws.brake_nm != 0.0) torque += ws.brake_nm * std::tanh(om_ctrl / rb.coulomb_smoothing_rad_s);
    const double current = torque / rb.torque_constant_nm_per_a;
    return torque * om + current * current * rb.coil_resistance_ohm;
  }
};

// The wheel-level state at one step's instant.
struct WheelStep {
  WheelState w;                 // rotation
  double c_l = 0.0, c_r = 0.0;  // controller rates omega_ctrl [rad/s]
  WheelSlip sl_l, sl_r;         // no episode acts at t = 0 (strength 0 at t0_s)
  double ref_l = 0.0, ref_r = 0.0;
};

// The state carried from one step to the next.
struct StepState {
  WheelStep wheels;
  double x = 0, y = 0, th = 0, v_prev = 0.0, w_prev = 0.0;
};

// The wheels at t1: the controller (actuator lag), the slip episodes and the
// rotation.
WheelStep wheel_step(const Physics& ph, const WheelStep& s0, const Command& cmd, double t1) {
  const double D = ph.D, h = ph.h;
  WheelStep s1;
  s1.ref_l = (cmd.v_m_s - cmd.w_rad_s * D / 2.0) / ph.R_l;
  s1.ref_r = (cmd.v_m_s + cmd.w_rad_s * D / 2.0) / ph.R_r;
  s1.c_l = ph.lag_e * s0.c_l + ph.one_minus_e * s0.ref_l + (s1.ref_l - s0.ref_l) * ph.lag_ramp;
  s1.c_r = ph.lag_e * s0.c_r + ph.one_minus_e * s0.ref_r + (s1.ref_r - s0.ref_r) * ph.lag_ramp;
  s1.sl_l = ph.wheel_slip(t1, SlipEpisode::Wheel::left);
  s1.sl_r = ph.wheel_slip(t1, SlipEpisode::Wheel::right);
  s1.w.om_l = s1.c_l * (1.0 - s1.sl_l.hold);
  s1.w.om_r = s1.c_r * (1.0 - s1.sl_r.hold);
  s1.w.phi_l = s0.w.phi_l + 0.5 * (s0.w.om_l + s1.w.om_l) * h;
  s1.w.phi_r = s0.w.phi_r + 0.5 * (s0.w.om_r + s1.w.om_r) * h;
  return s1;
}

// The wheels' ground speeds over the step [m/s] (g_l, g_r): the rim speeds of
// the unbraked rotation (a held wheel's contact is dragged along at them),
// less longitudinal, zone and spin slip, plus the model terms.
std::pair<double, double> ground_speeds(const Scenario& sc, const Physics& ph, const StepState& s0,
                                        const WheelStep& w1, double Rb_l, double Rb_r, double t1) {
  const WheelStep& s = s0.wheels;
  const double h = ph.h;
  const double u0_l = ph.eff_radius(s.c_l, Rb_l) * s.c_l, u1_l = ph.eff_radius(w1.c_l, Rb_l) * w1.c_l;
  const double u0_r = ph.eff_radius(s.c_r, Rb_r) * s.c_r, u1_r = ph.eff_radius(w1.c_r, Rb_r) * w1.c_r;
  const double s_long_l = std::min(0.5, ph.k_slip * std::abs(u1_l - u0_l) / h);
  const double s_long_r = std::min(0.5, ph.k_slip * std::abs(u1_r - u0_r) / h);
  const bool zone = ph.in_zone(s0.x, s0.y);
  const double s_zone_l = zone ? ph.fx.slip_zone->s_l : 0.0;
  const double s_zone_r = zone ? ph.fx.slip_zone->s_r : 0.0;
  double g_l = 0.5 * (u0_l + u1_l) * (1.0 - s_long_l) * (1.0 - s_zone_l) *
               (1.0 - 0.5 * (s.sl_l.spin + w1.sl_l.spin));
  double g_r = 0.5 * (u0_r + u1_r) * (1.0 - s_long_r) * (1.0 - s_zone_r) *
               (1.0 - 0.5 * (s.sl_r.spin + w1.sl_r.spin));
  if (!sc.terms.empty()) {  // model terms (docs/simulator.md, step 5a); none: every bit as before
    const TermState ts{g_l,
                       g_r,
                       (u1_l - u0_l) / h,
                       (u1_r - u0_r) / h,
                       0.5 * (g_r + g_l),
                       (g_r - g_l) / ph.D_true,
                       0.5 * (s.w.phi_l + w1.w.phi_l),
                       0.5 * (s.w.phi_r + w1.w.phi_r),
                       s0.x,
                       s0.y,
                       t1 - 0.5 * h};
    g_l += term_correction(sc.terms, TermTarget::v_l, ts);
    g_r += term_correction(sc.terms, TermTarget::v_r, ts);
  }
  return {g_l, g_r};
}

// Moves the pose over the step at body velocities (v, w) with lateral skid.
void advance_pose(const Physics& ph, double v, double w, StepState& s) {
  const double h = ph.h;
  const double vy = -ph.k_skid * v * w;
  const double half = 0.5 * w * h;
  core::arc_advance(&s.x, &s.y, &s.th, half, core::sinc(half) * h, v, vy, w * h);
}

// The true state at the end of the step (pose already advanced in s).
Truth truth_row(const Physics& ph, const StepState& s, const WheelStep& w1, double v, double w, double Rb_l,
                double Rb_r) {
  const RobotParams& rb = ph.rb;
  const double h = ph.h;
  const WheelState& w0 = s.wheels.w;
  const double a = (v - s.v_prev) / h, alpha = (w - s.w_prev) / h;
  const double f_lin = 0.5 * rb.mass_kg * a;                      // [N] per wheel
  const double f_rot = rb.yaw_inertia_kg_m2 * alpha / ph.D_true;  // [N], + right
  return {s.x,
          s.y,
          s.th,
          v,
          w,
          ph.motor_power(w1.w.om_l, (w1.w.om_l - w0.om_l) / h, f_lin - f_rot, ph.eff_radius(w1.w.om_l, Rb_l),
                         w1.sl_l, w1.c_l),
          ph.motor_power(w1.w.om_r, (w1.w.om_r - w0.om_r) / h, f_lin + f_rot, ph.eff_radius(w1.w.om_r, Rb_r),
                         w1.sl_r, w1.c_r)};
}

// The wheel state at every odometry query in (k, k+1], interpolated.
void interpolate_odometry(const std::vector<double>& q, std::int64_t k, const WheelState& w0,
                          const WheelState& w1, std::vector<WheelState>& odo, std::size_t& next_q) {
  const std::size_t n_rows = q.size();
  const double kd1 = static_cast<double>(k + 1);
  while (next_q < n_rows && q[next_q] <= kd1) {
    const double a = q[next_q] - static_cast<double>(k);  // in (0, 1]
    WheelState& o = odo[next_q++];
    o.phi_l = w0.phi_l + a * (w1.phi_l - w0.phi_l);
    o.phi_r = w0.phi_r + a * (w1.phi_r - w0.phi_r);
    o.om_l = w0.om_l + a * (w1.om_l - w0.om_l);
    o.om_r = w0.om_r + a * (w1.om_r - w0.om_r);
  }
}

// Integrates the run step by step: the true state at every row and the wheel
// state at every odometry query.
void integrate(const Scenario& sc, const MotionProfile& profile, const RowGrid& grid,
               const std::vector<double>& q, double spsd, const Physics& ph, std::vector<Truth>& truth,
               std::vector<WheelState>& odo) {
  const std::size_t n_rows = grid.row_k.size();
  std::size_t next_row = 0, next_q = 0;
  StepState s;
  const MotionParams& mo = sc.motion;
  s.x = mo.start_x_m, s.y = mo.start_y_m, s.th = mo.start_theta_rad;
  if (n_rows > 0 && grid.row_k[0] == 0) truth[next_row++] = Truth{s.x, s.y, s.th, 0.0, 0.0, 0.0, 0.0};
  while (next_q < n_rows && q[next_q] <= 0.0) odo[next_q++] = s.wheels.w;

  for (std::int64_t k = 0; k < grid.n_steps; ++k) {
    const double t1 = static_cast<double>(k + 1) / spsd;
    const WheelStep w1 = wheel_step(ph, s.wheels, profile.at(t1), t1);
    const double Rb_l = ph.base_radius(t1, false), Rb_r = ph.base_radius(t1, true);
    const auto [g_l, g_r] = ground_speeds(sc, ph, s, w1, Rb_l, Rb_r, t1);

    const double v = 0.5 * (g_r + g_l);
    const double w = (g_r - g_l) / ph.D_true;
    advance_pose(ph, v, w, s);

    if (next_row < n_rows && grid.row_k[next_row] == k + 1)
      truth[next_row++] = truth_row(ph, s, w1, v, w, Rb_l, Rb_r);
    interpolate_odometry(q, k, s.wheels.w, w1.w, odo, next_q);
    s.wheels = w1;
    s.v_prev = v;
    s.w_prev = w;
  }
}

// odometry_bias (docs/simulator.md, "Sensors"): the wheel-rate offsets whose
// NOMINAL forward kinematics are (b_v, b_w), added to the reported rates
// and, times the measurement time, to the counted rotation. Only when the
// effect is on, so tracks without it keep their bits.
void add_odometry_bias(const Physics& ph, const std::vector<double>& q, double spsd,
                       std::vector<WheelState>& odo) {
  const auto& ob = ph.fx.odometry_bias;
  const double D = ph.D;
  const double bias_om_l = ob ? (ob->b_v - ob->b_w * D / 2.0) / ph.R_l : 0.0;  // [rad/s]
  const double bias_om_r = ob ? (ob->b_v + ob->b_w * D / 2.0) / ph.R_r : 0.0;
  if (ob) {
    for (std::size_t r = 0; r < q.size(); ++r) {
      const double t_meas = q[r] / spsd;  // t - dt, clamped to the run like the odometry
      odo[r].phi_l += bias_om_l * t_meas;
      odo[r].phi_r += bias_om_r * t_meas;
      odo[r].om_l += bias_om_l;
      odo[r].om_r += bias_om_r;
    }
  }
}

void write_encoders(const RowGrid& grid, const std::vector<WheelState>& odo, const Scenario& sc,
                    tracks::TrackData& d) {
  const SensorParams& sp = sc.sensors;
  const std::size_t n_rows = grid.row_k.size();
  d.ticks_l.assign(n_rows, tracks::kNoTick);
  d.ticks_r.assign(n_rows, tracks::kNoTick);
  const bool om = sp.encoders.omega;
  if (om) d.ensure(tracks::Col::omega_l), d.ensure(tracks::Col::omega_r);
  const double per_rad = sc.robot.ticks_per_rev / kTwoPi;
  for (std::size_t r = 0; r < n_rows; ++r) {
    if (!grid.sampled(r, kEnc)) continue;
    d.ticks_l[r] = static_cast<std::int64_t>(std::floor(odo[r].phi_l * per_rad));
    d.ticks_r[r] = static_cast<std::int64_t>(std::floor(odo[r].phi_r * per_rad));
    if (om) {
      d.col(tracks::Col::omega_l)[r] = quantise(odo[r].om_l, sp.encoders.omega_resolution_rad_s);
      d.col(tracks::Col::omega_r)[r] = quantise(odo[r].om_r, sp.encoders.omega_resolution_rad_s);
    }
  }
}

void write_commands(const RowGrid& grid, const std::vector<double>& q, double spsd,
                    const MotionProfile& profile, const Scenario& sc, tracks::TrackData& d) {
  const SensorParams& sp = sc.sensors;
  const auto& ob = sc.effects.odometry_bias;
  auto& vc = d.ensure(tracks::Col::v_cmd);
  auto& wc = d.ensure(tracks::Col::w_cmd);
  for (std::size_t r = 0; r < grid.row_k.size(); ++r) {
    if (!grid.sampled(r, kCmd)) continue;
    Command c = profile.at(q[r] / spsd);
    if (ob) c.v_m_s += ob->b_v, c.w_rad_s += ob->b_w;
    vc[r] = quantise(c.v_m_s, sp.commands.resolution);
    wc[r] = quantise(c.w_rad_s, sp.commands.resolution);
  }
}

void write_gyro(const RowGrid& grid, const std::vector<Truth>& truth, const Scenario& sc,
                tracks::TrackData& d) {
  const SensorParams& sp = sc.sensors;
  const Effects& fx = sc.effects;
  Normal noise = make_stream(sc.seed, kGyroStream);
  auto& gz = d.ensure(tracks::Col::gyro_z);
  const double gs = fx.gyro_scale ? fx.gyro_scale->s : 1.0;
  const double gb = fx.gyro_bias ? fx.gyro_bias->b : 0.0;
  for (std::size_t r = 0; r < grid.row_k.size(); ++r)
    if (grid.sampled(r, kGyro))
      gz[r] = quantise(gs * truth[r].w + gb + sp.gyro.sigma_rad_s * noise(), sp.gyro.resolution_rad_s);
}

void write_power(const RowGrid& grid, const std::vector<Truth>& truth, const Scenario& sc,
                 tracks::TrackData& d) {
  const SensorParams& sp = sc.sensors;
  Normal noise = make_stream(sc.seed, kPowerStream);
  auto& pl = d.ensure(tracks::Col::power_l);
  auto& pr = d.ensure(tracks::Col::power_r);
  for (std::size_t r = 0; r < grid.row_k.size(); ++r) {
    if (!grid.sampled(r, kPower)) continue;
    pl[r] = quantise(truth[r].p_l + sp.power.sigma_w * noise(), sp.power.resolution_w);
    pr[r] = quantise(truth[r].p_r + sp.power.sigma_w * noise(), sp.power.resolution_w);
  }
}

void write_ext_velocity(const RowGrid& grid, const std::vector<Truth>& truth, const Scenario& sc,
                        tracks::TrackData& d) {
  Normal noise = make_stream(sc.seed, kExtStream);
  const auto& e = sc.sensors.ext_velocity;
  auto& ve = d.ensure(tracks::Col::v_ext);
  auto& we = d.ensure(tracks::Col::w_ext);
  auto& vv = d.ensure(tracks::Col::v_ext_var);
  auto& wv = d.ensure(tracks::Col::w_ext_var);
  const double var_v = tidy_variance(e.sigma_v_m_s), var_w = tidy_variance(e.sigma_w_rad_s);
  for (std::size_t r = 0; r < grid.row_k.size(); ++r) {
    if (!grid.sampled(r, kExt)) continue;
    ve[r] = quantise(truth[r].v + e.sigma_v_m_s * noise(), e.resolution);
    we[r] = quantise(truth[r].w + e.sigma_w_rad_s * noise(), e.resolution);
    vv[r] = var_v;
    wv[r] = var_w;
  }
}

void write_aps(const RowGrid& grid, const std::vector<Truth>& truth, const Scenario& sc, tracks::TrackData& d) {
  const SensorParams& sp = sc.sensors;
  Normal noise = make_stream(sc.seed, kApsStream);
  auto& ax = d.ensure(tracks::Col::aps_x);
  auto& ay = d.ensure(tracks::Col::aps_y);
  for (std::size_t r = 0; r < grid.row_k.size(); ++r) {
    if (!grid.sampled(r, kAps)) continue;
    ax[r] = quantise(truth[r].x + sp.aps.sigma_m * noise(), sp.aps.resolution_m);
    ay[r] = quantise(truth[r].y + sp.aps.sigma_m * noise(), sp.aps.resolution_m);
  }
}

void write_ground_truth(const RowGrid& grid, const std::vector<Truth>& truth, const Scenario& sc,
                        tracks::TrackData& d) {
  Normal noise = make_stream(sc.seed, kGtStream);
  const auto& gt = sc.sensors.ground_truth;
  auto& gx = d.ensure(tracks::Col::gt_x);
  auto& gy = d.ensure(tracks::Col::gt_y);
  auto& gth = d.ensure(tracks::Col::gt_theta);
  for (std::size_t r = 0; r < grid.row_k.size(); ++r) {
    if (!grid.sampled(r, kGt)) continue;
    gx[r] = quantise(truth[r].x + gt.sigma_m * noise(), gt.resolution_m);
    gy[r] = quantise(truth[r].y + gt.sigma_m * noise(), gt.resolution_m);
    gth[r] = quantise(truth[r].theta + gt.sigma_rad * noise(), gt.resolution_rad);
  }
}

// The sim.* metadata: seed, scenario, effects, episodes, terms, robot and the
// enabled sensors' rates and noise.
void add_metadata(const Scenario& sc, const RowGrid& grid, tracks::TrackMeta& meta) {
  const RobotParams& rb = sc.robot;
  const SensorParams& sp = sc.sensors;
  const auto& period = grid.period;
  auto& ex = meta.extra;
  auto put = [&ex](std::string key, double value) {
    ex.emplace_back(std::move(key), fmt::format("{}", value));
  };
  ex.emplace_back("sim.seed", fmt::format("{}", sc.seed));
  if (!sc.source.empty()) ex.emplace_back("sim.scenario", sc.source);
  ex.emplace_back("sim.effects", format_effects(sc.effects));
  // Only with episodes, so tracks without any keep their earlier bytes.
  if (!sc.slip_episodes.empty()) ex.emplace_back("sim.slip_episodes", format_slip_episodes(sc.slip_episodes));
  if (!sc.terms.empty()) ex.emplace_back("sim.terms", format_terms(sc.terms));  // likewise
  put("sim.step_s", sc.step_s);
  put("sim.max_accel_m_s2", sc.motion.max_accel_m_s2);
  put("sim.max_angular_accel_rad_s2", sc.motion.max_angular_accel_rad_s2);
  put("sim.robot.mass_kg", rb.mass_kg);
  put("sim.robot.yaw_inertia_kg_m2", rb.yaw_inertia_kg_m2);
  put("sim.robot.wheel_inertia_kg_m2", rb.wheel_inertia_kg_m2);
  put("sim.robot.viscous_friction_nm_s", rb.viscous_friction_nm_s);
  put("sim.robot.coulomb_friction_nm", rb.coulomb_friction_nm);
  put("sim.robot.coulomb_smoothing_rad_s", rb.coulomb_smoothing_rad_s);
  put("sim.robot.torque_constant_nm_per_a", rb.torque_constant_nm_per_a);
  put("sim.robot.coil_resistance_ohm", rb.coil_resistance_ohm);
  if (period[kEnc] > 0) put("sim.encoders_rate_hz", sp.encoders.rate_hz);
  if (period[kCmd] > 0) put("sim.commands_rate_hz", sp.commands.rate_hz);
  if (period[kGyro] > 0) {
    put("sim.gyro_rate_hz", sp.gyro.rate_hz);
    put("sim.gyro_sigma_rad_s", sp.gyro.sigma_rad_s);
  }
  if (period[kPower] > 0) {
    put("sim.power_rate_hz", sp.power.rate_hz);
    put("sim.power_sigma_w", sp.power.sigma_w);
  }
  if (period[kExt] > 0) {
    put("sim.ext_rate_hz", sp.ext_velocity.rate_hz);
    put("sim.ext_sigma_v_m_s", sp.ext_velocity.sigma_v_m_s);
    put("sim.ext_sigma_w_rad_s", sp.ext_velocity.sigma_w_rad_s);
  }
  if (period[kAps] > 0) {
    put("sim.aps_rate_hz", sp.aps.rate_hz);
    put("sim.aps_sigma_m", sp.aps.sigma_m);
  }
  if (period[kGt] > 0) {
    put("sim.gt_rate_hz", sp.ground_truth.rate_hz);
    put("sim.gt_sigma_m", sp.ground_truth.sigma_m);
    put("sim.gt_sigma_rad", sp.ground_truth.sigma_rad);
  }
}

}  // namespace

bool validate_scenario(const Scenario& sc, std::string* why) {
  const std::int64_t sps = steps_per_second(sc.step_s);
  if (sps == 0)
    return core::invalid(why, fmt::format("step_s = {}; expected a step in (0, 0.1] s whose inverse is a whole "
                                          "number of steps per second (e.g. 0.001)",
                                          sc.step_s));
  if (!check_robot(sc.robot, why) || !check_sensors(sc.sensors, sc.step_s, sps, why)) return false;

  const std::array<std::pair<const char*, double>, 3> start = {
      {{"x_m", sc.motion.start_x_m}, {"y_m", sc.motion.start_y_m}, {"theta_rad", sc.motion.start_theta_rad}}};
  for (const auto& [name, v] : start)
    if (!std::isfinite(v))
      return core::invalid(why, fmt::format("motion.start.{} = {}; expected a finite number", name, v));

  std::string ewhy;
  if (!validate_effects(sc.effects, &ewhy)) return core::invalid(why, "effects: " + ewhy);
  if (!validate_slip_episodes(sc.slip_episodes, &ewhy)) return core::invalid(why, ewhy);
  if (!validate_terms(sc.terms, &ewhy)) return core::invalid(why, "terms: " + ewhy);

  double duration = 0.0;
  if (!check_motion(sc, &duration, why)) return false;
  return check_size(sc, sps, duration, why);
}

tracks::Track simulate(const Scenario& sc) {
  std::string why;
  if (!validate_scenario(sc, &why)) throw std::invalid_argument(why);

  const MotionProfile profile(sc.motion);
  const std::int64_t sps = steps_per_second(sc.step_s);
  const double spsd = static_cast<double>(sps);
  const double h = 1.0 / spsd;  // [s]
  const RowGrid grid = row_grid(sc.sensors, profile, sps);
  const std::size_t n_rows = grid.row_k.size();
  const std::vector<double> q = odometry_queries(grid, sc.effects, spsd);

  const Physics ph(sc, h);
  std::vector<Truth> truth(n_rows);
  std::vector<WheelState> odo(n_rows);
  integrate(sc, profile, grid, q, spsd, ph, truth, odo);

  tracks::TrackData d;
  d.meta.name = sc.name;
  d.meta.origin = "simulated";
  d.meta.ticks_per_rev = sc.robot.ticks_per_rev;
  d.meta.wheel_radius_left_m = ph.R_l;
  d.meta.wheel_radius_right_m = ph.R_r;
  d.meta.wheel_base_m = ph.D;
  d.t.resize(n_rows);
  for (std::size_t r = 0; r < n_rows; ++r) d.t[r] = static_cast<double>(grid.row_k[r]) / spsd;

  add_odometry_bias(ph, q, spsd, odo);
  if (grid.period[kEnc] > 0) write_encoders(grid, odo, sc, d);
  if (grid.period[kCmd] > 0) {
    write_commands(grid, q, spsd, profile, sc, d);
    d.meta.body_velocity = tracks::BodyVelocitySource::commanded;  // the motion profile's commands
  }
  if (grid.period[kGyro] > 0) write_gyro(grid, truth, sc, d);
  if (grid.period[kPower] > 0) write_power(grid, truth, sc, d);
  if (grid.period[kExt] > 0) write_ext_velocity(grid, truth, sc, d);
  if (grid.period[kAps] > 0) write_aps(grid, truth, sc, d);
  if (grid.period[kGt] > 0) write_ground_truth(grid, truth, sc, d);
  add_metadata(sc, grid, d.meta);
  return tracks::Track(std::move(d));
}

}  // namespace odotune::sim

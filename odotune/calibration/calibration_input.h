// A track laid out for odometry calibration: the wheel rates of every
// odometry row (for dead reckoning), the calibration samples (wheel rates at
// each external velocity measurement, odotune/filters/odometry_params.h), the ground
// truth, the robot's nominal parameters and, for a simulated track, the true
// parameters over time (from its `sim.effects` metadata).
#pragma once

#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <odotune/filters/odometry_params.h>
#include <odotune/tracks/track.h>

namespace odotune::calibration {

// The true odometry parameters as a piecewise-constant function of time.
// Built from nominal metadata and the sim.effects of ../shared/specs/
// physics-effects.md: radius_error (R·scale), wheel_base_error (D·scale),
// radius_step (from t on, radii × its scales).
// A radius_step at t holds from t on (t included), as in the simulator.
struct TruthSchedule {
  std::vector<double> from_s;                   // start of each piece [s], increasing; from_s[0] = −∞
  std::vector<filters::OdometryParams> params;  // the truth during each piece

  // The piece holding t_s (the last with from_s ≤ t_s). Throws
  // std::logic_error on an empty schedule.
  const filters::OdometryParams& at(double t_s) const;
  // Times at which the truth changes (from_s[1..]).
  std::vector<double> change_times() const;
};

struct CalibrationInputOptions {
  // 0: external velocities from the track's v_ext/w_ext columns. > 0: derive
  // them from the ground truth at this rate [Hz] (a stand-in for lidar scan
  // matching on tracks that have none, e.g. OptiOdom with OptiTrack), by a
  // central difference of the pose over one period. At most 1000 Hz.
  double ext_from_gt_rate_hz = 0.0;
  // Velocities derived from the ground truth: their variances from the
  // reference's own jitter (reference_jitter.h: var_v = 2σ_xy²/T²,
  // var_w = 2σ_θ²/T² for a difference of poses T = 1/rate apart) plus the
  // wheel rates' encoder quantisation over wheel_rate_window_s (ticks only:
  // var_ω = (2π/ticks_per_rev)²/6/window² per wheel, so var_V += R²var_ω/2
  // and var_W += 2R²var_ω/D²). false: default_v_var/default_w_var.
  bool estimate_ext_noise = true;
  // Variances used when the track has no v_ext_var/w_ext_var (and for
  // velocities derived from the ground truth when estimate_ext_noise is
  // false).
  double default_v_var = 4e-4;  // [(m/s)²]
  double default_w_var = 4e-4;  // [(rad/s)²]
  // A sample's wheel rates are the mean over this window centred on the
  // measurement's time [s] (the wheel angle turned between the odometry rows
  // at or before t ∓ window/2, over their time apart); 0: the rate of the
  // single odometry interval ending at or before the measurement. One
  // encoder interval (10 ms of an 8800-count wheel) quantises ω to 0.07 rad/s;
  // a 0.1 s window cuts that tenfold, which matters for W and for the
  // errors-in-variables bias it puts on D. Online, it means holding a
  // measurement back half a window (50 ms) until the encoders have caught up.
  double wheel_rate_window_s = 0.1;
  // false: a track without external velocities (and without ground truth to
  // derive them from) is accepted with no calibration sample, for the
  // methods that need none (the pose-domain fit, pose_calibration.h, which
  // uses the ground truth or the position fixes). Velocities are still built
  // when the track has them or ext_from_gt_rate_hz > 0.
  bool require_velocity_samples = true;

  bool IsValid(std::string* why) const;
};

struct CalibrationInput {
  std::string track_name;
  filters::OdometryParams nominal;     // the track's robot.* metadata
  std::optional<TruthSchedule> truth;  // simulated tracks only

  // Odometry rows: the track rows with an odometry sample (both ticks, or
  // both omega columns; ticks win when a track has both), t[i] and the wheel
  // rates over (t[i−1], t[i]]: from ticks Δticks·2π/ticks_per_rev/Δt over the
  // previous tick row (row 0 has no interval: rates 0); from omega columns
  // the row's own sample (row 0 included).
  std::vector<double> t;                 // [s]
  std::vector<double> omega_l, omega_r;  // [rad/s]
  // Ground truth at those rows: the row's own sample when it has one, else
  // the linear interpolation of the ground-truth rows around it (NaN outside
  // the ground truth or across a gap > 0.5 s). Only rows with gt_x, gt_y AND
  // gt_theta count as ground truth.
  std::vector<double> gt_x, gt_y, gt_theta;  // [m, m, rad], theta unwrapped
  bool has_gt = false;                       // ≥ 2 ground-truth poses
  // Row r has a ground-truth pose (x, y and θ).
  bool has_gt_row(std::size_t r) const {
    return !std::isnan(gt_x[r]) && !std::isnan(gt_y[r]) && !std::isnan(gt_theta[r]);
  }

  // Absolute position fixes (aps_x, aps_y) stamped within the odometry's
  // time span [t.front(), t.back()], in time order.
  std::vector<double> fix_t, fix_x, fix_y;  // [s, m, m]
  // Their variances (aps_var_x, aps_var_y) where the track gives both, NaN
  // elsewhere.
  std::vector<double> fix_var_x, fix_var_y;  // [m²]

  // One calibration sample per external measurement, in time order, with the
  // odometry row it belongs to (sample_row: index into t, the last odometry
  // row at or before the measurement); its wheel rates are the mean over
  // CalibrationInputOptions::wheel_rate_window_s centred on the measurement.
  // A measurement with no odometry rate at or before it (before the second
  // tick row) is skipped. dt_s: time since the previous sample (0 for the
  // first); variances: v_ext_var/w_ext_var of the row when present and > 0,
  // else the options' defaults (always the defaults when derived from GT).
  std::vector<filters::CalibSample> samples;
  // How the samples' variances were set, one line (e.g. "derived from the
  // ground truth at 10 Hz; σ_v = 0.0051 m/s, σ_w = 0.029 rad/s from its
  // jitter (σ_xy = 0.19 mm, σ_θ = 1.43 mrad) and the encoders"); empty
  // without samples.
  std::string ext_noise;
  double ext_sigma_v_m_s = 0.0, ext_sigma_w_rad_s = 0.0;  // derived samples' σ (0: from the track)
  std::vector<std::size_t> sample_row;
  std::vector<double> sample_t;  // [s]
};

// External velocities derived from the ground truth (ext_from_gt_rate_hz =
// f > 0, period T = 1/f): one sample at each t_k = k/f (k integer) whose
// window [t_k − T/2, t_k + T/2] lies inside the ground truth, by
// central_difference_velocity (pose_series.h); the ground-truth samples
// around each window end must be at most 2T apart, else t_k is skipped. Its
// odometry row is the last at or before t_k (a row stamped < 1 µs after t_k
// counts as at t_k).
//
// Throws std::invalid_argument (one line naming the track and what is
// missing: wheel odometry, nominal radii/base/ticks_per_rev, external
// velocities or ground truth to derive them from, any usable sample; the
// last two only with require_velocity_samples, or when velocities are
// available but none is usable) and for
// invalid options or a malformed sim.effects.
CalibrationInput build_calibration_input(const tracks::Track& track, const CalibrationInputOptions& options);

// The truth of a simulated track (nullopt when it has no sim.effects or the
// nominal radii/base metadata is missing). sim.effects is the "; "-separated
// list of odotune/sim/effects.h (parse_effect_spec per part, "none" for no
// effect). Only the geometric effects enter the truth (radius_error,
// wheel_base_error, radius_step); the others (speed_radius, slips, ...) are
// ignored, so under them the truth is the static geometry. Throws
// std::invalid_argument naming the track on a malformed sim.effects.
std::optional<TruthSchedule> truth_from_metadata(const tracks::TrackMeta& meta);

}  // namespace odotune::calibration

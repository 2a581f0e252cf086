// A track laid out for velocity fusion and learned odometry at one fixed rate
// (Fariña et al., Sensors 2023, 23, 961, ../shared/papers/002_*.txt: the
// wheelchair's odometry, lidar and gyro are fused at 10 Hz and the LSTMs see
// 10 Hz encoder increments). Step k covers the interval (t[k−1], t[k]];
// every per-step quantity below is over that interval, so a network's inputs
// and its targets describe the same motion.
#pragma once

#include <string>
#include <vector>

#include <optional>

#include <odotune/filters/odometry_params.h>
#include <odotune/tracks/odometry_input.h>
#include <odotune/tracks/track.h>

namespace odotune::learned {

struct FusionInputOptions {
  double rate_hz = 10.0;  // fusion / network rate (paper: 10 Hz); (0, 1000]
  // The odometry to read (odotune/tracks/odometry_input.h); nullopt: the track's own.
  std::optional<tracks::OdometryInput> input;
  // Calibrated kinematics: wheels through this geometry instead of the
  // track's nominal one; a twist or commands scaled and delayed
  // (odotune/filters/odometry_params.h, TwistCorrection). Default: nominal.
  std::optional<filters::OdometryParams> geometry;
  filters::TwistCorrection twist;
  // > 0: external velocities derived from the ground truth at this rate
  // [Hz] (a stand-in for the paper's Velodyne, where a dataset has only its
  // reference pose): at each t = j / rate the central difference of the
  // ground truth over one period (odotune/objectives/pose_series.h), variances
  // default_ext_var_*; these replace the track's v_ext, w_ext. At most 100 Hz.
  double ext_from_gt_hz = 0.0;
  // Variances used where the track has external velocities but no
  // v_ext_var/w_ext_var [(m/s)², (rad/s)²].
  double default_ext_var_v = 4e-4;
  double default_ext_var_w = 4e-4;
  bool IsValid(std::string* why) const;
};

struct FusionInput {
  std::string track_name;
  tracks::OdometryInput input = tracks::OdometryInput::wheels;  // what v_kin, w_kin come from
  filters::OdometryParams nominal;  // the track's robot.* metadata, or options.geometry (wheels only)
  double ticks_per_rev = 0.0;       // encoder counts per wheel revolution (wheels only; else 0)
  double dt_s = 0.1;                // 1 / rate_hz
  // Step times [s]: t[0] = the first odometry row's time, t[k] = t[0] + k·dt
  // while an odometry row exists at or after it (the last step ends at or
  // before the last odometry row). Step 0 has no interval: its per-step
  // values are 0 (increments, velocities) or NaN (sensors).
  std::vector<double> t;
  // Wheel-rotation increments over the step in encoder counts (the paper's
  // Δct); from the tick columns (linear interpolation of the cumulative
  // count at t[k]; a row stamped within 1 µs of t[k] gives its own count) or,
  // without ticks, ∫ω dt · ticks_per_rev / 2π (trapezoid over the omega
  // rows). Real-valued because of the interpolation. NaN for a twist or
  // command input.
  std::vector<double> dticks_l, dticks_r;
  // The nominal kinematic odometry over the step [m/s, rad/s]: wheels, paper
  // eqs. 1–2 with the nominal radii and base; twist and commands, the mean of
  // v_cmd, w_cmd over the step under odotune/tracks/body_velocity.h's zero-order
  // hold. With FusionInputOptions::geometry or twist, the calibrated one.
  std::vector<double> v_kin, w_kin;
  // Mean motor power over the step [W] (mean of the power rows inside it);
  // NaN when none.
  std::vector<double> power_l, power_r;
  // The last external velocity measurement inside the step and its variances
  // (track's v_ext_var/w_ext_var when present and > 0, else the defaults);
  // NaN when none.
  std::vector<double> v_ext, w_ext, v_ext_var, w_ext_var;
  // Mean gyro yaw rate over the step [rad/s] (mean of the rows inside); NaN
  // when none.
  std::vector<double> gyro_z;
  // The track's velocity commands (v_cmd, w_cmd) over the step, under
  // odotune/tracks/body_velocity.h's hold, whatever the odometry is [m/s, rad/s];
  // NaN without them. (For a commands input, v_kin before any calibration.)
  std::vector<double> v_cmd, w_cmd;
  // The last position fix inside the step [m] and its variances [m²] (the
  // track's aps_var_x/aps_var_y; NaN where it gives none); NaN when none.
  std::vector<double> fix_x, fix_y, fix_var_x, fix_var_y;
  // Ground truth: the pose at t[k] (the gt row stamped within 1 µs of t[k],
  // else the linear interpolation of gt rows; theta unwrapped; NaN outside
  // the ground truth or across a gap > 0.5 s) and the mean body velocities
  // over the step from it (NaN where a pose is missing):
  //   W = Δθ/Δt,  V = (Δx·cos θ̄ + Δy·sin θ̄)/Δt,  θ̄ = (θ_{k−1} + θ_k)/2.
  std::vector<double> gt_x, gt_y, gt_theta;
  std::vector<double> v_true, w_true;
  bool has_gt = false, has_power = false, has_ext = false, has_gyro = false, has_fixes = false, has_cmd = false;

  std::size_t size() const { return t.size(); }
};

// Steps [first, end) of `in` as an input of their own (t, the per-step
// series and the flags; end clamped to in.size()): a part of a recording to
// score on its own.
FusionInput slice_fusion_input(const FusionInput& in, std::size_t first, std::size_t end);

// Throws std::invalid_argument with one line naming the track and what is
// missing or wrong (no odometry of the requested kind, a v_cmd/w_cmd track
// that does not say what they are, odotune/tracks/odometry_input.h; for wheels the
// nominal radii/base/ticks_per_rev absent; fewer than 2 steps, invalid
// options).
FusionInput build_fusion_input(const tracks::Track& track, const FusionInputOptions& options = {});

}  // namespace odotune::learned

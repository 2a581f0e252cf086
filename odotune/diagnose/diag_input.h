// A track laid out for the sim-to-real diagnosis (docs/diagnosis-design.md):
// the odometry as measured, the gyro, the nominal robot and the reference,
// as plain arrays in SI units. Built once per track; the diagnosis never
// touches the Track again.
#pragma once

#include <string>
#include <vector>

#include <odotune/tracks/track.h>

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
  std::vector<double> v_mps, w_radps;        // body_velocity: samples of v, w (the model
                                             // takes them linear between stamps, see effect_model.h)
  // body_velocity: what v, w are, in words: "command" (v_cmd/w_cmd as the
  // track format defines them), or "velocity odometry" when the metadata's
  // source.note says they are measured (e.g. Lost in the Woods); "" otherwise.
  std::string velocity_source;

  // Commanded body velocities when the track has them alongside wheel odometry
  // (for actuator_lag), same times as odo_t_s; empty otherwise.
  std::vector<double> cmd_v_mps, cmd_w_radps;

  // Gyro (empty when the track has none).
  std::vector<double> gyro_t_s, gyro_z_radps;

  // Reference samples, strictly increasing time, within the odometry's span:
  // ground truth, position fixes, or both (see build_diag_input).
  ReferenceKind reference = ReferenceKind::gt;  // the source of most samples
  std::vector<double> ref_t_s, ref_x_m, ref_y_m;
  std::vector<double> ref_theta_rad;  // unwrapped; empty without a heading on every sample
  // Standard deviation of one reference position sample [m] of the source of
  // most samples: from the track's metadata when it states one (sim.*), else
  // estimated (see build_diag_input).
  double ref_sigma_m = 0.0;
  // Standard deviation of one reference heading sample [rad] (ref_theta_rad
  // non-empty only; NaN otherwise): metadata sim.gt_sigma_rad, else estimated.
  double ref_sigma_rad = 0.0;
  // Per reference sample: (ref_sigma_m / that sample's sigma)^2, the weight of
  // its squared position error against a sample of sigma ref_sigma_m. Empty =
  // every sample has sigma ref_sigma_m (one source).
  std::vector<double> ref_w;
  std::size_t ref_gt_samples = 0, ref_fix_samples = 0;  // samples of each source

  // Window starts fixed from outside [s], used by make_windows (window_replay.h)
  // for windows of fixed_window_s instead of its own rule: a thinned copy of
  // an input (the selection's, cross_validate.h) keeps its raw input's
  // windows. Empty: make_windows' rule. Cleared by crop and concatenate.
  std::vector<double> fixed_window_starts_s;
  double fixed_window_s = 0.0;

  // Weight of reference sample i (1 without ref_w).
  double ref_weight(std::size_t i) const { return ref_w.empty() ? 1.0 : ref_w[i]; }
  bool has_ref_heading() const { return !ref_theta_rad.empty(); }
};

// Throws std::invalid_argument (one line naming the track and what is
// missing) when the track has no usable odometry or reference.
//
// Odometry: ticks_l/r when present (rotation = ticks*2*pi/ticks_per_rev since
// the first row holding both), else omega_l/r integrated by the trapezoid rule,
// else v_cmd/w_cmd as body_velocity. With wheel odometry and v_cmd/w_cmd,
// cmd_* holds the commands linearly interpolated at odo_t_s (first/last value
// held outside their span). Wheel odometry needs the nominal radii and base.
// Reference: every reference the track has, in any
// mix. Ground truth = gt_x/gt_y rows (with gt_theta, unwrapped, when every such
// row has it); fixes = aps_x/aps_y rows that ground truth does not already
// cover (no ground-truth sample within 1.5 of its median intervals: fixes
// beside dense ground truth add only noise); both only within the odometry's
// time span. One source: its samples as they are (ground truth keeps its
// heading). Both (a known start plus fixes, ground truth with gaps filled by
// fixes): their positions merged in time order, each weighted by its own noise
// (ref_w); no heading, since fixes carry none; `reference` names the source of
// most samples. Gaps, irregular rates and a single sample are all accepted here;
// the diagnosis says when too few samples leave nothing to fit.
// Sigmas per source: metadata sim.gt_sigma_m / sim.gt_sigma_rad /
// sim.aps_sigma_m, else a robust estimate from that source's own samples:
// consecutive samples against the nominal dead-reckoned chord between them,
// sigma = 1.4826*MAD(|d_ref| - |d_odo|)/sqrt(2) over the intervals where the
// odometry moved (where it moved more than 3 sigma, once 10 such intervals
// exist), needing 3 samples (a source with fewer, e.g. a known start pose,
// borrows the other source's sigma); floored at 1 mm.
// ref_sigma_rad likewise from sim.gt_sigma_rad, else
// 1.4826*MAD(d_theta_ref - d_theta_odo)/sqrt(2), floored at 1 mrad. The
// estimates include the odometry's own error over one reference interval, so
// they are upper bounds of the reference noise.
// Throws only when the track has no reference column or no reference sample
// within the odometry's time span (one line saying so).
// sim.effects is never read: the diagnosis must find effects from the data.
DiagInput build_diag_input(const tracks::Track& track);

// The samples of `in` with t_s in [t0_s, t1_s] (odometry, commands, gyro,
// reference); wheel angles re-zeroed at the first kept odometry sample;
// sigmas and the nominal robot kept. Throws std::invalid_argument (one line)
// when the interval is empty or leaves fewer than 2 odometry or reference
// samples.
DiagInput crop(const DiagInput& in, double t0_s, double t1_s);

}  // namespace odotune::diagnose

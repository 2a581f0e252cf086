// Running an odometry calibration method over one or more tracks and scoring
// it: the estimates over time, convergence time, velocity and pose errors of
// the calibrated odometry against ground truth, and cost per iteration.
//
// Methods (Fariña, Toledo & Acosta, RA-L 2026, Tables I–II):
//   adaptive-pf, pf  odotune/filters/pf_calibrator.h (online)
//   dkf              odotune/filters/dual_kf.h (online)
//   online-pose      odotune/filters/pose_calibrator.h (online, from position fixes;
//                    odotune/calibration/online_pose.h)
//   batch-pose       odotune/calibration/pose_calibration.h (offline: dead reckoning
//                    fitted to the reference positions; `batch` is its alias)
//   batch-velocity   odotune/calibration/batch_calibration.h (offline least squares
//                    on body velocities)
//   none             the track's nominal parameters
// Online methods run the tracks one after another with the same filter (as
// UMBmark combines a clockwise and a counter-clockwise run); batch fits all
// tracks at once.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/online_pose.h>
#include <odotune/calibration/pose_calibration.h>
#include <odotune/filters/dual_kf.h>
#include <odotune/filters/memory_pair.h>
#include <odotune/filters/pf_calibrator.h>

namespace odotune::calibration {

enum class CalibrationMethod { adaptive_pf, pf, dkf, online_pose, batch_pose, batch_velocity, none };
inline constexpr std::array<CalibrationMethod, 7> kAllCalibrationMethods = {
    CalibrationMethod::adaptive_pf, CalibrationMethod::pf,         CalibrationMethod::dkf,
    CalibrationMethod::online_pose, CalibrationMethod::batch_pose, CalibrationMethod::batch_velocity,
    CalibrationMethod::none};
// "adaptive-pf", "pf", "dkf", "online-pose", "batch-pose", "batch-velocity",
// "none".
std::string_view to_string(CalibrationMethod m);
// Also accepts "batch" for batch-pose (the pose fit beat the velocity fit on
// the real OptiOdom runs, docs/calibration/real-data.md).
bool parse_calibration_method(std::string_view text, CalibrationMethod* out);
// batch-pose or batch-velocity: one fit of fixed parameters to all tracks.
inline bool is_offline(CalibrationMethod m) {
  return m == CalibrationMethod::batch_pose || m == CalibrationMethod::batch_velocity;
}

struct CalibrationOptions {
  CalibrationMethod method = CalibrationMethod::adaptive_pf;
  // pf and adaptive-pf. The method sets pf.adaptive (true for adaptive-pf,
  // false for pf); for adaptive-pf a particle count left at the plain
  // default (PfCalibratorParams{}.particles, 5000) becomes the adaptive
  // initial count of PfCalibratorParams::adaptive_defaults() (8000, §V),
  // any other count is kept. The ranges, seed etc. are used as given (set
  // them around the robot's nominal values).
  filters::PfCalibratorParams pf;
  filters::DualKfParams dkf;
  PoseCalibrationOptions pose;    // batch-pose
  OnlinePoseOptions online_pose;  // online-pose
  // pf/adaptive-pf with the evidence evolution, dkf with fading memory and
  // online-pose run as a slow/fast pair that finds changes (odotune/filters/memory_pair.h).
  filters::MemoryPairParams memory_pair;
  // Convergence: the first time after which R_R, R_L and D all stay within
  // this fraction of the truth (the paper: 0.5 %; see TrackCalibrationScore).
  double convergence_tolerance = 0.005;
  // Checks the tolerance (in (0, 1)) and the parameters of the chosen method
  // (pf with the adaptive rule above applied; dkf), *why prefixed "pf." or
  // "dkf.".
  bool IsValid(std::string* why) const;
};

// The PF parameters the method runs with (the adaptive rule above applied).
filters::PfCalibratorParams effective_pf_params(const CalibrationOptions& options);

// Estimates over time: one row per iteration (per measurement) of an online
// method (online-pose: per position fix, where its geometry changes). The fixed-parameter methods (batch, none) have one row per track,
// at the track's first sample, with the constants (batch: with its sds).
struct CalibrationTrace {
  std::vector<double> t;   // [s], on the track's clock (per track)
  std::vector<int> track;  // index of the track the row belongs to
  std::vector<filters::CalibEstimate> estimate;
};

// Scores of one track. The parameters current at time t are those of the
// last iteration at or before t (the filter's initial estimate before the
// first; fixed methods: the constants).
//
// Convergence (per piece of the truth schedule, calibration_input.h): the
// earliest sample time after which R_R and R_L both stay within the
// tolerance of the truth at every later sample of the piece (until the end of
// the track or the next truth change); see convergence_time(). Fixed
// parameters (none, score_fixed_params) converge at the piece's first sample
// when they are within the tolerance, never otherwise; batch reports none
// (an offline fit has no convergence over time).
//
// Dead reckoning: from the first odometry row with ground truth, at its pose,
// each later odometry row's wheel rates over its interval Δt are integrated
// with filters::diff_drive_step (l = ω_l R_L Δt, r = ω_r R_R Δt) using the
// parameters current at the row; the pose is compared at every later row with
// ground truth (heading differences wrapped to (−π, π]). V/W errors: at each
// sample with ground truth around it, body_velocity(current params, the
// sample's wheel rates) against the ground-truth central-difference velocity
// over ±0.05 s (pose_series.h).
struct TrackCalibrationScore {
  std::string track;
  filters::OdometryParams final_params;                // at the end of this track
  std::optional<filters::OdometryParams> truth_final;  // truth at the track's last odometry row
  // Since the track's first odometry row [s]; nullopt: no truth, or never
  // converged before the end of the first piece.
  std::optional<double> convergence_time_s;
  // One per change of the truth (radius_step), in time order: time from the
  // change to re-converging [s]; nullopt when it never does (or the change
  // lies after the track's last sample).
  std::vector<std::optional<double>> reconvergence_s;
  double pose_rmse_m = 0.0;       // RMSE(x, y) of the calibrated odometry vs GT (NaN: no GT)
  double heading_rmse_rad = 0.0;  // RMSE θ (NaN: no GT)
  double v_rmse_m_s = 0.0;        // calibrated odometry V vs GT-derived V (NaN: no GT)
  double w_rmse_rad_s = 0.0;      // W likewise
};

struct CalibrationResult {
  CalibrationMethod method = CalibrationMethod::none;
  filters::OdometryParams final_params;  // after the last track
  std::vector<TrackCalibrationScore> tracks;
  CalibrationTrace trace;
  // Online methods: step() calls, and their wall time (std::chrono::
  // steady_clock) / iterations [ms]. batch: the residual pairs, and the wall
  // time of the whole fit / pairs (cost per measurement). none: 0 and 0.
  long iterations = 0;
  double ms_per_iteration = 0.0;
  double mean_particles = 0.0;  // PF: mean N over iterations (deterministic cost); else 0
  bool memory_pair = false;  // an online method run as a slow/fast memory pair (odotune/filters/memory_pair.h)
  long memory_restarts = 0;  // ... and the changes it found (else 0)
  // online-pose: the memory it ran with (online_pose_memory of the inputs).
  std::optional<filters::DistanceMemoryParams> online_pose_memory;
  // batch methods only: Ceres reported convergence (the fit's sds are in the
  // trace row), and which residuals the fit used.
  bool batch_converged = false;
  std::string batch_residuals;
};

// Runs `options.method` over the inputs in order. The calibrated odometry is
// dead-reckoned from each track's first ground-truth pose with the
// parameters estimated up to that instant (online methods) or the fitted ones
// (batch: fitted to all inputs from the first input's nominal values; none:
// each track's own nominal values). Throws std::invalid_argument for invalid
// options, no inputs or a null input.
CalibrationResult run_calibration(const std::vector<const CalibrationInput*>& inputs,
                                  const CalibrationOptions& options);

// Dead-reckoning scores of fixed parameters on one track (what `--apply`
// reports for a held-out run). Throws std::invalid_argument (naming the
// track) for invalid parameters or an input without odometry rows.
TrackCalibrationScore score_fixed_params(const CalibrationInput& input, const filters::OdometryParams& params,
                                         double convergence_tolerance = 0.005);

// The dead-reckoned path of fixed parameters on one track (the dead
// reckoning of TrackCalibrationScore): from the first odometry row with
// ground truth, at its pose, one point per later odometry row, with the
// ground truth at that row (NaN where it has none). Empty without ground
// truth. Throws std::invalid_argument for invalid parameters.
struct DeadReckonedPath {
  std::vector<double> t, x, y;     // [s, m, m]
  std::vector<double> gt_x, gt_y;  // [m]
};
DeadReckonedPath dead_reckoned_path(const CalibrationInput& input, const filters::OdometryParams& params);

// The earliest times[i] such that estimates[j] is within `tolerance` of
// `truth` (|est − truth| ≤ tolerance·truth for R_R and R_L: the radii, as
// the paper's convergence time, Fariña et al. §VI; D is reported, not
// required) for every j ≥ i; nullopt when the series is empty or its last estimate is outside.
// times and estimates have equal lengths (std::invalid_argument otherwise).
std::optional<double> convergence_time(const std::vector<double>& times,
                                       const std::vector<filters::OdometryParams>& estimates,
                                       const filters::OdometryParams& truth, double tolerance);

}  // namespace odotune::calibration

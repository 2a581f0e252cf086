// The --json documents of `odotune calibrate` (nlohmann_json). Unknown or
// undefined numbers (no truth, no ground truth, never converged) are null.
//
// Calibration (`"mode": "calibrate"`):
//   format              "odotune-calibration-result/1"
//   method              adaptive-pf | pf | dkf | batch | none
//   final               {wheel_radius_left_m, wheel_radius_right_m, wheel_base_m} after the last track
//   final_sd            the same keys: spread of the last estimate (PF weighted sd, KF √P); null without a trace
//   truth, error_pct    truth at the end of the last track and 100·(final − truth)/truth; null when unknown
//   convergence_time_s  of the first track (the time from the initial guess until every radius and the
//                       wheel base stay within the tolerance of the truth); null when unknown or never
//   pose_rmse_m, heading_rmse_rad   of the calibrated odometry against ground truth, mean over the
//                       tracks with ground truth; nominal_pose_rmse_m, nominal_heading_rmse_rad likewise
//                       with the tracks' nominal parameters
//   ms_per_iteration, iterations, mean_particles   (batch: per residual pair, pairs, 0;
//                       plus batch_converged)
//   options             what ran: initial ranges, resampler, policy, seed, particles, …
//   tracks[]            per track: track, file, final, truth, error_pct, convergence_time_s,
//                       reconvergence [{change_at_s, time_s}], pose_rmse_m, heading_rmse_rad,
//                       v_rmse_m_s, w_rmse_rad_s, nominal {pose_rmse_m, heading_rmse_rad}, iterations
//
// Replay of a calibration file (`"mode": "apply"`):
//   format, calibration {file, wheel_radius_left_m, wheel_radius_right_m, wheel_base_m},
//   tracks[] {track, file, nominal {params, pose_rmse_m, heading_rmse_rad},
//             calibrated {pose_rmse_m, heading_rmse_rad}, improvement_pct {pose, heading}},
//   mean {nominal, calibrated} of the pose and heading RMSE over the tracks.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_run.h>

namespace odotune::formats {

// What `calibrate` ran, beyond the result itself.
struct CalibrationRunInfo {
  std::vector<std::string> track_files;  // as given, in input order
  calibration::CalibrationOptions options;
  filters::PfCalibratorParams::Range init_radius_m, init_wheel_base_m;  // initial ranges
  double ext_from_gt_rate_hz = 0.0;                                     // 0: the tracks' v_ext/w_ext
};

// `nominal[k]` scores inputs[k]'s nominal parameters (score_fixed_params).
nlohmann::json calibration_json(const calibration::CalibrationResult& result,
                                const std::vector<const calibration::CalibrationInput*>& inputs,
                                const std::vector<calibration::TrackCalibrationScore>& nominal,
                                const CalibrationRunInfo& info);

// One held-out track of `--apply`.
struct AppliedTrack {
  std::string file;
  filters::OdometryParams nominal_params;
  calibration::TrackCalibrationScore nominal, calibrated;
};

nlohmann::json apply_json(const std::string& calibration_file, const filters::OdometryParams& params,
                          const std::vector<AppliedTrack>& tracks);

// 100·(a − b)/a, the improvement of RMSE b over a in % (positive = b is
// smaller); NaN when a is not a positive number or either is not finite.
double rmse_improvement_pct(double a, double b);

}  // namespace odotune::formats

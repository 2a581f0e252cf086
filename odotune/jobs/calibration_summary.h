// The text `odotune calibrate` prints: the summary of a calibration run
// (method and initial ranges, per track the final estimate against the
// truth, convergence, re-convergence after truth changes, pose and heading
// RMSE against the nominal parameters, the cost) and of an --apply replay.
// Lengths in metres, angles in radians, as printed.
#pragma once

#include <string>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_run.h>
#include <odotune/filters/odometry_params.h>
#include <odotune/formats/calibration_json.h>

namespace odotune::jobs {

// `nominal[k]` scores inputs[k]'s nominal parameters; `info` says what ran.
std::vector<std::string> calibration_summary_lines(
    const calibration::CalibrationResult& result, const std::vector<calibration::CalibrationInput>& inputs,
    const std::vector<calibration::TrackCalibrationScore>& nominal, const formats::CalibrationRunInfo& info);

// "applied FILE (R_L = …) to N tracks, …:" and each track's pose and heading RMSE.
std::vector<std::string> apply_summary_lines(const std::string& calibration_file,
                                             const filters::OdometryParams& params,
                                             const std::vector<formats::AppliedTrack>& tracks);

}  // namespace odotune::jobs

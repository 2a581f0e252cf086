// Calibrated odometry parameters as YAML, the file `calibrate --config-out`
// writes and `calibrate --apply` reads:
//
//   # calibrated by odotune calibrate: method adaptive-pf, tracks a.csv, b.csv, ...
//   format: odotune-calibration/1
//   wheel_radius_left_m: 0.31682    # R_L [m]
//   wheel_radius_right_m: 0.32379   # R_R [m]
//   wheel_base_m: 0.65021           # D [m], between the wheel contact points
//
// The leading comment lines record the provenance (method, tracks, seed);
// the reader ignores them. Reading errors are one line:
// "FILE:LINE: what is wrong, what was expected".
#pragma once

#include <filesystem>
#include <string>

#include "filters/odometry_params.h"

namespace odotune {

struct CalibrationFile {
  filters::OdometryParams params;
  std::string comment;  // written as leading YAML comment lines (provenance); not read back
};

// Throws odotune::Failure (FILE:LINE: reason).
CalibrationFile read_calibration_file(const std::filesystem::path& path);
// The file's text (what write_calibration_file writes).
std::string format_calibration_file(const CalibrationFile& file);
// Writes atomically (temporary + rename). Throws odotune::Failure.
void write_calibration_file(const CalibrationFile& file, const std::filesystem::path& path);

}  // namespace odotune

// Calibrated odometry parameters as YAML, the file `calibrate --config-out`
// writes and `calibrate --apply` reads:
//
//   # calibrated by odotune calibrate: method adaptive-pf, tracks a.csv, b.csv, ...
//   format: odotune-calibration/1
//   wheel_radius_left_m: 0.31682    # R_L [m]
//   wheel_radius_right_m: 0.32379   # R_R [m]
//   wheel_base_m: 0.65021           # D [m], between the wheel contact points
//
// or, for a body-velocity odometry (a twist the drive reports, or commands;
// odotune/calibration/twist_calibration.h):
//
//   format: odotune-calibration/1
//   odometry: commands              # twist | commands (absent: wheels, the keys above)
//   scale_v: 0.9102                 # v = scale_v · v_cmd(t − delay_s)
//   scale_w: 0.9871                 # w = scale_w · w_cmd(t − delay_s)
//   delay_s: 0.25                   # [s]
//
// The leading comment lines record the provenance (method, tracks, seed);
// the reader ignores them. Reading errors are one line:
// "FILE:LINE: what is wrong, what was expected".
#pragma once

#include <filesystem>
#include <string>

#include <odotune/filters/odometry_params.h>
#include <odotune/tracks/odometry_input.h>

namespace odotune::formats {

struct CalibrationFile {
  tracks::OdometryInput odometry = tracks::OdometryInput::wheels;  // what the file calibrates
  filters::OdometryParams params;                                  // wheels
  filters::TwistCorrection twist;                                  // twist and commands
  std::string comment;  // written as leading YAML comment lines (provenance); not read back
};

// Throws core::Failure (FILE:LINE: reason).
CalibrationFile read_calibration_file(const std::filesystem::path& path);
// The file's text (what write_calibration_file writes).
std::string format_calibration_file(const CalibrationFile& file);
// Writes atomically (temporary + rename). Throws core::Failure.
void write_calibration_file(const CalibrationFile& file, const std::filesystem::path& path);

}  // namespace odotune::formats

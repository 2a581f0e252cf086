// `--controller-out` of `calibrate` and `diagnose`: the flags as plain
// values, their checks (before the long work), the geometry each command
// hands to odotune/formats/controller_config.h, and the line the command prints.
//
// Flags (docs/calibration/README.md, "Into the robot's controller"):
//   --controller-out FILE and --controller ros2_control|ros1|gazebo go
//   together; --controller-form multipliers|absolute (default multipliers)
//   and --controller-name NAME (default diff_drive_controller) need them and
//   apply to the ROS controllers only; --nominal-wheel-radius-m R and
//   --nominal-wheel-base-m D (calibrate only) replace the nominal geometry
//   the multipliers refer to (default: the first track's robot.* metadata).
// Every refusal is an core::Failure naming the flag.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <odotune/calibration/calibration_run.h>
#include <odotune/diagnose/diagnosis.h>
#include <odotune/diagnose/recordings.h>
#include <odotune/filters/odometry_params.h>
#include <odotune/formats/controller_config.h>

namespace odotune::jobs {

struct ControllerRequest {
  std::string out;                               // --controller-out FILE; "" = no controller file
  std::optional<std::string> kind;               // --controller: ros2_control | ros1 | gazebo
  std::optional<std::string> form;               // --controller-form: multipliers (default) | absolute
  std::optional<std::string> name;               // --controller-name; default diff_drive_controller
  std::optional<double> nominal_wheel_radius_m;  // --nominal-wheel-radius-m [m] (calibrate)
  std::optional<double> nominal_wheel_base_m;    // --nominal-wheel-base-m [m] (calibrate)

  bool any_given() const;
};

// Checks the flags together and the output path (odotune/core/output_paths.h); call
// it before the long work. Throws core::Failure naming the flag: one of
// --controller-out and --controller without the other, an unknown kind or
// form, a malformed name, --controller-form or --controller-name with
// gazebo, a nominal override that is not a finite length > 0 [m], or (when
// !nominal_flags_allowed) a nominal override at all.
formats::ControllerOptions check_controller_request(const ControllerRequest& request,
                                                    bool nominal_flags_allowed);

// Throws core::Failure "FLAG does not combine with CONTEXT" for the first
// controller flag given (e.g. with calibrate --apply).
void refuse_controller_flags(const ControllerRequest& request, const std::string& context);

// What a calibration run found, as the controller file's input: the final
// estimate (online methods: the estimate after the last track, as
// --config-out), the nominal (the first input's, or the overrides), and the
// provenance (method, seed of the PF methods, tracks, the estimate's sd, the
// dead-reckoning pose RMSE on the calibrated tracks: not held out).
formats::ControllerGeometry calibration_controller_geometry(
    const ControllerRequest& request, const calibration::CalibrationResult& result,
    const std::vector<calibration::TrackCalibrationScore>& nominal_scores,
    const filters::OdometryParams& track_nominal, const std::string& method_line,
    const std::vector<std::string>& track_files);

// The corrected geometry of a diagnosis: the nominal robot × the fitted
// scales of radius_error (scale_l, scale_r) and wheel_base_error (scale)
// (../shared/specs/physics-effects.md); nullopt when neither was found.
// Provenance: the effects, their fitted size ± stderr, the other findings
// (not in the file) and, in `heldout`, each effect's held-out position error
// without → with it, the held-out recordings' test when there are some.
std::optional<formats::ControllerGeometry> diagnosis_controller_geometry(
    const diagnose::Diagnosis& diagnosis, const diagnose::PooledDiagnosis* pooled,
    const filters::OdometryParams& track_nominal, const std::vector<std::string>& fit_files,
    const std::vector<std::string>& heldout_files);

// The track's nominal robot as diagnose reads it (odotune/diagnose/diag_input.h);
// throws core::Failure naming --controller-out and the track when it has
// no positive radii and wheel base (body-velocity odometry without robot.*).
filters::OdometryParams diagnosis_track_nominal(const diagnose::DiagInput& input, const std::string& file);

// Writes the file (atomically) and returns the line the command prints:
// "controller: FILE (ros2_control diff_drive_controller, multipliers form:
// wheel_radius … m × left … right …, wheel_separation … m × …)". Throws
// core::Failure.
std::string write_controller_file(const ControllerRequest& request, const formats::ControllerOptions& options,
                                  const formats::ControllerGeometry& geometry);

}  // namespace odotune::jobs

// `odotune calibrate` on tracks whose odometry is a body velocity, a twist
// the drive measured or the commands (odotune/tracks/odometry_input.h):
// odotune/calibration/twist_calibration.h's pose-domain fit of scales (and a delay
// for commands) by --method batch, its calibration file and JSON, and
// --apply of such a file on held-out tracks. run_calibrate and
// run_calibrate_apply (odotune/jobs/calibrate_job.h) hand such tracks here.
#pragma once

#include <optional>
#include <vector>

#include <odotune/formats/calibration_yaml.h>
#include <odotune/jobs/calibrate_job.h>
#include <odotune/tracks/track.h>

namespace odotune::jobs {

// The body-velocity input of the request's tracks (each track's own, or
// --input), or nullopt for wheel tracks. Throws Failure (one line naming
// the file) when a track's odometry cannot be told or the tracks mix kinds.
std::optional<tracks::OdometryInput> calibrate_body_input(const CalibrateRequest& a,
                                                          const std::vector<tracks::Track>& tracks);

// Refuses the flags that do not apply to a body-velocity fit, fits, writes
// --config-out and --json. Throws Failure.
CalibrateOutcome run_twist_calibrate(const CalibrateRequest& a, const std::vector<tracks::Track>& tracks,
                                     tracks::OdometryInput input);

// --apply of a twist or commands calibration file: every track's dead
// reckoning at the identity and at the file's correction; writes --json.
// Throws Failure when the tracks' odometry is not the file's.
ApplyOutcome run_twist_apply(const CalibrateRequest& a, const formats::CalibrationFile& file,
                             const std::vector<tracks::Track>& tracks);

}  // namespace odotune::jobs

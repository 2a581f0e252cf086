// A robot's bag made ready to replay in one call: the recording as
// load_recording makes it and, when asked, navsat_transform_node's GPS-to-odom
// rotation fitted on its first seconds (odotune/rlnode/gps_alignment.h) and
// fixed in it; then refused if navsat could never take its datum.
#pragma once

#include <filesystem>
#include <optional>

#include <odotune/rlnode/gps_alignment.h>
#include <odotune/rlnode/params.h>
#include <odotune/rlnode/recording.h>

namespace odotune::rlnode {

struct PreparedRecording {
  Recording rec;                          // with the fitted transform, when there is one
  std::optional<GpsAlignment> alignment;  // the fit (gps_heading_fit_s > 0)
};

// gps_heading_fit_s > 0: the rotation fitted on the recording's first
// gps_heading_fit_s seconds with robot_localization's default process noise and
// initial covariance rather than the file's, so that it does not change with
// the noise being tuned (a tuned file then replays to the figures its tune
// reported); the fit replaces Recording::gps_transform. Throws
// std::invalid_argument (one line naming the bag): load_recording's and
// fit_gps_alignment's refusals, and a bag whose fixes reach navsat without a
// fixed transform, an IMU orientation or use_odometry_yaw (no heading for its
// datum).
PreparedRecording prepare_recording(const std::filesystem::path& bag, const RlParams& params,
                                    const RecordingOptions& options, double gps_heading_fit_s = 0.0);

}  // namespace odotune::rlnode

// navsat_transform_node's rotation between the GPS grid and the odom frame,
// fitted instead of taken from the IMU's heading (for IMUs whose absolute yaw
// cannot be trusted): the filter is replayed without GPS over the first
// `seconds` of the recording, and the rotation and offset that best map the
// fixes onto its positions at their stamps (least squares in the plane,
// Umeyama's closed form without scale) become a fixed GpsTransform.
#pragma once

#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>

namespace odotune::rlnode {

struct GpsAlignment {
  GpsTransform transform;
  int fixes = 0;        // fixes used
  double span_m = 0.0;  // their largest distance from their mean
  double rms_m = 0.0;   // residual after the fit
  double yaw_offset_rad =
      0.0;  // navsat's yaw_offset that gives this rotation (when the IMU's heading is known)
};

// Throws std::invalid_argument (one line) when the recording has no GPS
// input, or the fixes of the first `seconds` number fewer than 5 or span
// less than 5 m (too little driving to see the heading).
GpsAlignment fit_gps_alignment(const Recording& rec, const ReplaySettings& settings, double seconds);

}  // namespace odotune::rlnode

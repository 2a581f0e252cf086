// Odometry (learned or kinematic) fused with absolute position fixes: the
// learned-odometry paper's fusion (odotune/learned/ukf_fusion.h; Fariña et al.,
// Sensors 2023, 23, 961, Fig. 1) with the pose in the filter's state
// (odotune/filters/pose_velocity_ukf.h), so that the fixes of a GNSS, UWB or
// motion-capture system correct the dead-reckoned path. Per step k ≥ 1 of a
// FusionInput: predict over Δt, update with the odometry's (V, W) and its
// variances, with the gyro (noise.use_gyro) and the external velocity
// (noise.use_external) where the step has them, and with the step's fix.
//
// The filter starts at step 0's ground-truth pose (σ start_sigma_m and
// start_sigma_rad) at rest, so that its error is the fusion's alone and
// comparable with dead reckoning from the same pose; a track without a
// ground-truth pose there starts at its first fix, heading 0 with σ π.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <odotune/filters/pose_velocity_ukf.h>
#include <odotune/learned/fusion_input.h>
#include <odotune/learned/ukf_fusion.h>
#include <odotune/objectives/metrics.h>

namespace odotune::learned {

struct PoseFusionOptions {
  filters::PoseUkfParams ukf;  // its initial state and covariance are set as the header says
  // σ of a fix where the track gives no aps_var_x/aps_var_y [m]; 0: such a
  // track is refused.
  double fix_sigma_m = 0.0;
  double start_sigma_m = 0.05, start_sigma_rad = 0.05;  // about the ground truth at step 0
  UkfSensorNoise noise;
  bool IsValid(std::string* why) const;
};

struct PoseFusionTrace {
  std::vector<double> x, y, theta, v, w;  // per step [m, m, rad, m/s, rad/s]
  std::size_t fixes = 0;                  // fixes fused
  bool healthy = true;                    // NaN from the step it turned unhealthy on
};

// Throws std::invalid_argument (one line naming the track) for invalid
// options, odo.size() != in.size(), a track without fixes, or a fix without
// a variance when fix_sigma_m is 0.
PoseFusionTrace replay_pose_fusion(const FusionInput& in, const std::vector<OdometryMeasurement>& odo,
                                   const PoseFusionOptions& options);

// Position error of the trace against the ground truth at steps k ≥ 1 [m].
objectives::ErrorMetrics pose_fusion_errors(const FusionInput& in, const PoseFusionTrace& trace);

}  // namespace odotune::learned

// Velocity fusion over a FusionInput: the UKF of odotune/filters/velocity_ukf.h fed,
// at the input's fixed rate, with the wheel odometry (v, w and its
// variances), the external body velocities (lidar scan matching) and the
// gyro, as in Fariña et al., "Improving Odometric Model Performance Based on
// LSTM Networks", Sensors 2023, 23, 961 (../shared/papers/002_*.txt, §1,
// Fig. 1); the pose is integrated from the filtered (V, W) by eq. 3 and scored
// against the ground truth by the position metrics of odotune/objectives/metrics.h.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <odotune/filters/velocity_ukf.h>
#include <odotune/learned/fusion_input.h>
#include <odotune/objectives/metrics.h>

namespace odotune::learned {

// Sensor variances of the fusion other than the odometry's.
struct UkfSensorNoise {
  double gyro_var = 4e-6;      // σ² of the gyro's W [(rad/s)²] (static, paper §1)
  double ext_var_scale = 1.0;  // multiplies the track's external-velocity variances [-]
  bool use_external = true, use_gyro = true;
  // gyro_var and ext_var_scale finite and > 0; `why` names the bad value.
  bool IsValid(std::string* why) const;
};

// One odometry measurement of the fusion, for one step.
struct OdometryMeasurement {
  double v_m_s = 0, w_rad_s = 0, var_v = 1e-3, var_w = 1e-3;  // [m/s, rad/s, (m/s)², (rad/s)²]
};

// The nominal kinematic odometry of `in` (v_kin, w_kin, paper eqs. 1–2) with
// static variances [(m/s)², (rad/s)²], one per step (step 0 included: 0, 0).
// Throws std::invalid_argument unless both variances are finite and > 0.
std::vector<OdometryMeasurement> static_odometry(const FusionInput& in, double var_v, double var_w);

// One fusion step k ≥ 1: predict(in.dt_s); update with the odometry
// (R = diag(var_v, var_w)); with the external velocity if present at k (and
// noise.use_external; R = diag(v_ext_var, w_ext_var)·ext_var_scale); with the
// gyro if present at k (and noise.use_gyro; variance gyro_var). A non-finite
// or non-positive input makes the filter unhealthy (odotune/filters/velocity_ukf.h);
// nothing is thrown for it.
void fuse_step(filters::VelocityUkf& ukf, const FusionInput& in, std::size_t k, const OdometryMeasurement& odo,
               const UkfSensorNoise& noise);

struct FusionTrace {
  std::vector<double> v, w, var_v, var_w, cov_vw;  // filtered state and covariance per step
                                                   // [m/s, rad/s, (m/s)², (rad/s)², (m/s)(rad/s)]
  std::vector<double> x, y, theta;                 // pose integrated (eq. 3) from the filtered V, W
                                                   // [m, m, rad], starting at the GT pose at t[0]
                                                   // ((0, 0, 0) without a GT pose there)
  bool healthy = true;                             // the filter stayed healthy to the end
};

// Replays the whole input: the filter starts from params.initial_state and
// initial_cov (the defaults: at rest, ±0.1 m/s and ±0.1 rad/s; the tracks
// start at rest, and step 0 has no odometry interval to start from), step 0
// of the trace is that initial state, and step k ≥ 1 is fuse_step(k) with
// odo[k]. Once the filter turns unhealthy the remaining steps are NaN and
// `healthy` is false. Throws std::invalid_argument when odo.size() !=
// in.size() or for invalid params / noise (messages name the bad value).
FusionTrace replay_fusion(const FusionInput& in, const std::vector<OdometryMeasurement>& odo,
                          const filters::UkfParams& params, const UkfSensorNoise& noise);

// Position error of a trace against the ground truth: the planar distance
// between (x, y)[k] and (gt_x, gt_y)[k] over the steps k ≥ 1 that have a GT
// position (step 0 is the start pose) [m]. Zero samples without ground
// truth; NaN metrics when the trace holds non-finite positions (an unhealthy
// trace: callers check `healthy` first).
objectives::ErrorMetrics fusion_pose_errors(const FusionInput& in, const FusionTrace& trace);
// The same for any per-step positions x, y [m].
objectives::ErrorMetrics position_errors(const FusionInput& in, const std::vector<double>& x,
                                         const std::vector<double>& y);

}  // namespace odotune::learned

// Offline batch calibration: R_R, R_L and D fitted to whole tracks by least
// squares with Ceres (the classical offline method the online calibrators are
// compared with).
//
// Residuals, one pair per calibration sample (wheel rates + external
// velocity, odotune/calibration/calibration_input.h), whitened by the measurement's σ:
//   (V_odo(θ, ω) − V_m)/σ_v,  (W_odo(θ, ω) − W_m)/σ_w,
// with a Huber loss (scale 3σ, on the pair's norm) against outliers; the
// parameters are bounded below by 1 % of their initial values (positivity
// only). Standard errors from ceres::Covariance, scaled by the residual
// variance per degree of freedom (2·cost/(2n − 3)); NaN when a parameter is
// unobservable from the samples (e.g. D on a track that never turns).
#pragma once

#include <string>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/filters/odometry_params.h>

namespace odotune::calibration {

struct BatchCalibrationSummary {
  filters::OdometryParams params;
  double sd_radius_left_m = 0.0, sd_radius_right_m = 0.0, sd_wheel_base_m = 0.0;  // [m]
  long residual_pairs = 0;                                                        // samples used
  bool converged = false;                                                         // Ceres reported CONVERGENCE
  std::string termination;                                                        // Ceres' message
};

// Starts from `initial` (one thread, deterministic); throws
// std::invalid_argument when the inputs hold no samples (naming the tracks),
// for a null input or invalid initial parameters.
BatchCalibrationSummary batch_calibrate(const std::vector<const CalibrationInput*>& inputs,
                                        const filters::OdometryParams& initial);

}  // namespace odotune::calibration

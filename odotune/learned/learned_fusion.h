// The whole localisation system of Fariña et al., Sensors 2023, 23, 961
// (Figs. 1, 6, 7): odometry (learned or kinematic) with a variance (the slip
// detector's, or static), fused with the external (lidar) and gyro
// velocities by the (V, W) UKF (odotune/learned/ukf_fusion.h), with optional
// online retraining of the velocity nets (§4.2):
//
//   a step's window and the UKF's filtered (V, W) are kept as a retraining
//   sample when the filter's variances are below `max_filter_var_*` and the
//   odometry's below `max_odometry_var_*` ("the robot is well localised");
//   every `samples_per_retrain` (300) such samples both nets are refitted
//   from their current weights and the samples are dropped.
#pragma once

#include <optional>
#include <vector>

#include <odotune/filters/velocity_ukf.h>
#include <odotune/learned/learned_odometry.h>
#include <odotune/learned/slip_detector.h>
#include <odotune/learned/ukf_fusion.h>

namespace odotune::learned {

// The refit's solver settings: a few LM iterations at the final MAE scale
// from the current weights, with weight decay λ = 1 toward those weights
// (LstmTrainingOptions::decay_to_start). (No coarse-to-fine continuation of
// the loss scale: the warm start is already near an optimum, and the coarse
// stages of a fresh training pull it away — measured: with the continuation,
// the nets drifted further from the truth after each refit.) The decay: the
// targets are the filter's velocities, noisier than the nets on good drives,
// and 300 of them against ~190 weights let a free refit chase their noise.
// Measured on wheelchair_learn_step (scratch runs of 4 training seeds, the
// learned odometry's MAE after the radius step): a free refit left V worse
// than no refit on every seed (e.g. 0.0259 vs 0.0102 m/s), λ = 1 toward the
// current weights improved V and W on every seed (V 0.0090-0.0099 vs
// 0.0097-0.0110 m/s, W 0.0082-0.0146 vs 0.0159-0.0258 rad/s); λ = 0.3 and 3
// were close, with V worse than no refit on some seeds at 0.3.
inline LstmTrainingOptions default_retrain_training() {
  LstmTrainingOptions o;
  o.max_iterations = 10;
  o.mae_scale_start = o.mae_scale;
  o.weight_decay = 1.0;
  o.decay_to_start = true;
  return o;
}

struct RetrainOptions {
  bool enabled = false;
  int samples_per_retrain = 300;                                // paper §4.2
  double max_filter_var_v = 4e-4, max_filter_var_w = 4e-4;      // [(m/s)², (rad/s)²]
  double max_odometry_var_v = 5e-3, max_odometry_var_w = 5e-3;  // [(m/s)², (rad/s)²]
  LstmTrainingOptions training = default_retrain_training();
  bool IsValid(std::string* why) const;
};

struct LearnedFusionOptions {
  enum class Odometry { kinematic, learned } odometry = Odometry::learned;
  // Variable covariance from the slip detector when it is given; else the
  // static variances below.
  const SlipDetectorModel* detector = nullptr;
  double static_var_v = 1e-3, static_var_w = 1e-3;  // [(m/s)², (rad/s)²]
  filters::UkfParams ukf;
  UkfSensorNoise noise;
  RetrainOptions retrain;
  bool IsValid(std::string* why) const;
};

struct RetrainEvent {
  std::size_t step = 0;  // the step after which the nets were refitted
  double t_s = 0.0;
  double seconds = 0.0;  // wall time of both refits
  LstmTrainingSummary v, w;
};

struct LearnedFusionResult {
  OdometrySeries odometry;  // the odometry fed to the UKF, per step
  std::vector<double> odo_var_v, odo_var_w;
  FusionTrace filter;  // UKF state, covariance and integrated pose
  std::vector<RetrainEvent> retrains;
  std::optional<LearnedOdometryModel> final_model;  // after retraining (learned odometry only)
};

// `model` is needed (non-null) for learned odometry; it is copied, never
// modified. Throws std::invalid_argument on invalid options.
LearnedFusionResult run_learned_fusion(const FusionInput& in, const LearnedOdometryModel* model,
                                       const LearnedFusionOptions& options);

}  // namespace odotune::learned

// The work of `odotune learn train|eval|retrain`: the learned odometry of
// Fariña, Acosta, Toledo & Acosta, "Improving Odometric Model Performance
// Based on LSTM Networks", Sensors 2023, 23, 961 (odotune/learned/learned_odometry.h,
// the slip detector of odotune/learned/slip_detector.h, the UKF fusion with online
// retraining of odotune/learned/learned_fusion.h), on recorded or simulated tracks.
// Request in, files written, outcome and its lines of text out; the command
// reads the flags, shows the progress and prints the lines. The model file is
// odotune/results/learned_model_json.h, the JSON blocks odotune/studies/learned_study_outputs.h.
//
// Every function throws core::Failure with one line (naming the flag or
// the file) on bad requests or inputs, before long work where it can: an
// output path whose folder does not exist, too few iterations, a track
// without ground truth (or motor power / external velocities where needed),
// a model file that does not read or was trained for another robot.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <odotune/learned/fusion_input.h>
#include <odotune/learned/learned_fusion.h>
#include <odotune/learned/learned_odometry.h>
#include <odotune/learned/lstm_training.h>
#include <odotune/learned/odometry_metrics.h>
#include <odotune/learned/odometry_selection.h>
#include <odotune/learned/slip_detector.h>
#include <odotune/results/learned_model_json.h>

namespace odotune::studies {

// Progress of a job in steps (nets trained, fusion runs).
using LearnProgress = std::function<void(long done, long total)>;
// Calls `progress` when set.
inline void report_progress(const LearnProgress& progress, long done, long total) {
  if (progress) progress(done, total);
}

// ---------------------------------------------------------------- shared pieces

// Loads track files and lays them out for fusion at `rate_hz` from their
// `input` odometry (nullopt: each track's own; ext_from_gt_hz as
// FusionInputOptions); every track must have ground
// truth, and motor power when `need_power`. `purpose` ends the error line
// ("expected it " + purpose).
std::vector<learned::FusionInput> load_fusion_inputs(const std::vector<std::string>& files, double rate_hz,
                                                     bool need_power, const char* purpose,
                                                     std::optional<tracks::OdometryInput> input = std::nullopt,
                                                     double ext_from_gt_hz = 0.0);

std::vector<const learned::FusionInput*> fusion_pointers(const std::vector<learned::FusionInput>& v);

// `base`: a fresh training's defaults, or default_retrain_training() for refits.
learned::LstmTrainingOptions learn_training_options(std::uint64_t seed, int iterations, int threads,
                                                    learned::LstmTrainingOptions base = {});

// Pooled MAE of a series over several tracks (weighted by samples); NaN
// without samples.
double pooled_mae(const std::vector<learned::SeriesErrors>& e);

// results::read_learned_model with its one-line errors as Failure.
results::LearnedModelFile load_learned_model(const std::string& path);

// The model and the track must describe the same robot and odometry
// (odotune/learned/learned_odometry.h, model_fits). `file` names the track, `model`
// the model in the error line.
void check_model_fits(const results::LearnedModelFile& m, const learned::FusionInput& in,
                      const std::string& file, const std::string& model);

// ---------------------------------------------------------------- train

struct LearnTrainRequest {
  std::vector<std::string> tracks;       // with ground truth: the velocity nets
  std::vector<std::string> slip_tracks;  // with motor power: the slip detector (none: no detector)
  std::string model_out;                 // --model-out, required
  std::uint64_t seed = 1;
  // Ceres iterations per velocity net, ≥ 1 (correction nets: the cap of
  // their early stopping).
  int iterations = 100;
  int slip_iterations = 0;       // per detector net (0 = iterations)
  double rate_hz = 10.0;         // network rate [Hz], (0, 1000]
  double previous_noise = -1.0;  // σ on the teacher-forced previous V [m/s] and W [rad/s]; < 0 = the study's
  int threads = 1;               // OpenMP threads evaluating the windows; results do not depend on it
  std::optional<tracks::OdometryInput>
      input;  // --input; nullopt: each track's own (odotune/tracks/odometry_input.h)
  learned::LearnedTarget target =
      learned::LearnedTarget::correction;  // --target: the nets' output (odotune/learned/learned_odometry.h)
  // --validation; nullopt: chronological for the paper's nets; for
  // correction nets recordings with two tracks or more, else blocks.
  std::optional<learned::LearnedValidation> validation;
  // Correction nets (odotune/learned/odometry_selection.h): the blocks' length, the
  // folds, the early stopping's patience [iterations], the candidate
  // settings and whether to read the gyro.
  learned::SelectionOptions selection;
  std::string command;  // the model's provenance.created_by
};

struct LearnTrainOutcome {
  std::size_t tracks = 0, slip_tracks = 0;
  tracks::OdometryInput input = tracks::OdometryInput::wheels;
  learned::LearnedTrainingSummary odometry;                       // the paper's nets
  std::optional<learned::SelectionSummary> selection;             // correction nets
  std::optional<learned::SlipTrainingSummary> detector;           // when slip tracks were given
  learned::SlipDrive detector_drive = learned::SlipDrive::power;  // what its drive channels read
  double kinematic_v_mae = 0.0, kinematic_w_mae = 0.0;            // pooled over the training tracks
  learned::LearnedTarget target = learned::LearnedTarget::velocity;
  learned::LearnedValidation validation = learned::LearnedValidation::chronological;
  bool v_beats_kinematic = true, w_beats_kinematic = true;  // the model's (learned_odometry.h)
  std::string model_out;
};

// Trains the velocity nets (the paper's, or correction nets chosen by
// cross-validation) and, with slip tracks, the slip detector on the learned
// odometry's errors there, then writes the model file
// (odotune/studies/learn_train_job.cpp). Progress: the paper's nets 0, 1 (and 2) of
// 1 (2 with a detector); correction nets the fits of the cross-validation.
LearnTrainOutcome run_learn_train(const LearnTrainRequest& request, const LearnProgress& progress = {});
// The lines the command prints (without newlines): "learned odometry trained
// on …", the nets' MAEs, the kinematic odometry's, the detector's, "model: FILE".
std::vector<std::string> learn_train_lines(const LearnTrainOutcome& outcome);

// ---------------------------------------------------------------- eval

struct LearnEvalRequest {
  std::string track;  // with ground truth
  std::string model;  // model file
  // Optional: a calibration file (odotune calibrate --config-out) of the
  // model's odometry; its calibrated kinematics are scored too.
  std::string calibration;
  // Score only the steps from from_s on and before until_s [s, on the
  // track's clock] (the odometry still runs from the track's start).
  std::optional<double> from_s, until_s;
  // A track with position fixes: each odometry is also fused with them
  // (odotune/learned/pose_fusion.h); this σ [m] where a fix has no variance (0: such
  // fixes are not fused, and the lines say why).
  double fix_sigma_m = 0.0;
  std::string json;  // optional: errors of the learned and the kinematic odometry
  std::string csv;   // optional: velocities and dead-reckoned poses per step
};

struct LearnEvalOutcome {
  std::string track_name, file, model, json, csv;
  std::size_t steps = 0;
  double rate_hz = 0.0;                                     // the model's [Hz]
  bool v_beats_kinematic = true, w_beats_kinematic = true;  // the model's training verdict
  learned::OdometryErrors learned, kinematic;
  std::optional<learned::OdometryErrors> calibrated;  // with --calibration
  // Fused with the track's fixes: the position errors of each odometry's
  // fusion (calibrated with --calibration), the fixes fused; or why not.
  struct Fused {
    objectives::ErrorMetrics learned, kinematic;
    std::optional<objectives::ErrorMetrics> calibrated;
    std::size_t fixes = 0;
  };
  std::optional<Fused> fused;
  std::string not_fused;  // a track with fixes that could not be fused: why
  // The model's slip detector on the track (when it has one with flag
  // thresholds): the steps it flags, and the learned odometry's mean |error|
  // inside and outside them [m/s, rad/s].
  struct Flags {
    learned::SlipDrive drive = learned::SlipDrive::power;
    std::size_t steps = 0, flagged = 0;
    double v_in = 0, v_out = 0, w_in = 0, w_out = 0;
  };
  std::optional<Flags> slip;
};

// Scores the learned and the kinematic odometry (pose dead-reckoned from each;
// with --calibration also the calibrated kinematics) against the track's
// ground truth; writes the CSV, then the JSON.
LearnEvalOutcome run_learn_eval(const LearnEvalRequest& request);
// A first line when a net of the model did not beat the kinematics in its
// training; then "track … model …:", the learned and the kinematic
// odometry's errors, the files.
std::vector<std::string> learn_eval_lines(const LearnEvalOutcome& outcome);

// ---------------------------------------------------------------- retrain

struct LearnRetrainRequest {
  std::string track;  // with ground truth and external velocities (or --ext-from-gt)
  std::string model;  // model file to start from
  // > 0: the external velocities derived from the ground truth at this rate
  // [Hz] (FusionInputOptions::ext_from_gt_hz), for datasets whose reference
  // is a pose (motion capture), as the paper's Velodyne gave its velocities.
  double ext_from_gt_hz = 0.0;
  std::optional<double> until_s;   // retrain on the steps before this time only [s, the track's clock]
  std::string model_out;           // optional: the retrained model
  std::string json;                // optional: retrain events, errors with and without retraining
  int every = 300;                 // samples per retrain, ≥ 20
  int iterations = 10;             // Ceres iterations per refit, ≥ 1
  bool static_covariance = false;  // ignore the model's slip detector
  int threads = 1;
  std::string command;  // the retrained model's provenance.created_by
};

struct LearnRetrainOutcome {
  std::string track_name, file, model_out, json;
  int every = 0, iterations = 0;
  bool detector = false;                                    // slip-detector covariance (else static)
  bool v_beats_kinematic = true, w_beats_kinematic = true;  // the starting model's training verdict
  learned::RetrainOptions gate;                             // the retraining gate's thresholds
  std::vector<learned::RetrainEvent> retrains;
  learned::OdometryErrors retrained, fixed;  // the odometry fed to the UKF, with and without retraining
};

// Runs the UKF over the track with online retraining, then without (progress:
// 0, 1, 2 of 2 runs); writes the retrained model, then the JSON. The model's
// rate is the track's layout rate; retraining starts from the model's seed.
LearnRetrainOutcome run_learn_retrain(const LearnRetrainRequest& request, const LearnProgress& progress = {});
// The retrains (or why there was none), the odometry's errors with and
// without retraining, the files.
std::vector<std::string> learn_retrain_lines(const LearnRetrainOutcome& outcome);

}  // namespace odotune::studies

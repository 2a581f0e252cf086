// Learned odometry (Fariña, Acosta, Toledo & Acosta, "Improving Odometric
// Model Performance Based on LSTM Networks", Sensors 2023, 23, 961,
// ../shared/papers/002_*.txt, §4 and Fig. 4): two LSTMs, one for V and one
// for W, each seeing a window of 20 steps (10 Hz) of
//     (Δct_r, Δct_l, previous V)   resp.   (Δct_r, Δct_l, previous W)
// standardised (eq. 4), one layer of 5 units, linear output, trained with a
// robust (≈ MAE) loss against ground-truth velocities, 70 % of the windows
// for training and 30 % for validation (chronological split per track).
//
// "Previous velocity": during training the ground-truth velocity of the
// previous step (teacher forcing); when running, whatever the caller feeds
// back: the network's own previous output (odometry alone) or the fusion
// filter's previous estimate (inside the UKF, learned_fusion.h).
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "learned/fusion_input.h"
#include "learned/lstm.h"
#include "learned/lstm_training.h"

namespace odotune {

// What the velocity nets output: the body velocity itself (the paper's
// nets), or a correction added to the nominal kinematic velocity, so that a
// net that has learnt nothing reproduces the kinematic odometry.
enum class LearnedTarget { velocity, correction };
std::string_view to_string(LearnedTarget t);  // "velocity", "correction"
bool parse_learned_target(std::string_view text, LearnedTarget* out);

// What the nets are validated on (the restarts' choice and the correction
// nets' kinematic gate): the last (1 − train_fraction) of each track's steps
// (the paper's split), or whole recordings: the last
// max(1, round(N·(1 − train_fraction))) of the N tracks as given, which the
// nets never train on.
enum class LearnedValidation { chronological, recordings };
std::string_view to_string(LearnedValidation v);  // "chronological", "recordings"
bool parse_learned_validation(std::string_view text, LearnedValidation* out);

// The features of one step, in network input order.
enum LearnedFeature : int { kFeatDticksR = 0, kFeatDticksL = 1, kFeatPrevious = 2 };

struct LearnedOdometryModel {
  VelocityNet v_net, w_net;
  double rate_hz = 10.0;       // the step rate the nets were trained at
  double ticks_per_rev = 0.0;  // of the robot they were trained on (increments are in counts)
  LearnedTarget target = LearnedTarget::velocity;  // what the nets output (see LearnedTarget)
  // A correction net that did not beat the kinematic odometry on the
  // training's validation steps is zeroed (it outputs the kinematics) and
  // flagged false here; always true for velocity nets.
  bool v_beats_kinematic = true, w_beats_kinematic = true;
  // Validation MAE of each net at training time [m/s, rad/s] (the static
  // odometry variance falls back on it when there is no slip detector).
  double v_validation_mae = 0.0, w_validation_mae = 0.0;
  bool IsValid(std::string* why) const;
};

struct LearnedTrainingOptions {
  LstmTrainingOptions training;  // Ceres solve of each net
  double train_fraction = 0.7;   // paper: 70 / 30
  // Noise added to the teacher-forced previous velocity during training [m/s,
  // rad/s] (seeded); 0 = pure teacher forcing. A little noise teaches the nets
  // not to copy the previous velocity blindly, which matters when they run on
  // their own outputs.
  double previous_noise_v = 0.0, previous_noise_w = 0.0;
  // Independent initialisations per net (seeds training.seed + 7919·r, the W
  // net's + 1000), 1..100; kept is the one with the smallest free-running
  // MAE (the net fed its own previous output, as run_learned_odometry runs
  // it) over the last (1 − train_fraction) of each track's steps. LM from one
  // random start is unreliable on these nets: on wheelchair_learn with seeds
  // 1-5 the validation MAE of a single start ranged over two decades (V
  // 0.0016-0.21 m/s, W 0.0028-0.12 rad/s), the bad starts far worse than the
  // kinematic model; and a small one-step (teacher-forced) validation MAE
  // did not guarantee a net that stays on track on its own outputs.
  int restarts = 4;
  // correction: each net learns v_true − v_kin (w_true − w_kin) from a zero
  // output start (LstmTrainingOptions::zero_output_start).
  LearnedTarget target = LearnedTarget::velocity;
  LearnedValidation validation = LearnedValidation::chronological;
  bool IsValid(std::string* why) const;
};

struct LearnedTrainingSummary {
  LstmTrainingSummary v, w;                          // of the kept start
  int v_restart = 0, w_restart = 0;                  // which start was kept (0-based)
  std::vector<double> v_restart_mae, w_restart_mae;  // each start's free-running MAE [m/s, rad/s]
  // The kinematic odometry's MAE on the same validation steps [m/s, rad/s].
  double v_kinematic_mae = 0.0, w_kinematic_mae = 0.0;
  std::size_t train_windows = 0, validation_windows = 0;
  double seconds = 0.0;  // both nets, wall time
};

// The windows of one track: every step k ≥ window with ground truth over the
// whole window; target v_true[k] (resp. w_true[k]), minus v_kin[k] (w_kin[k])
// for a correction target. Appends to v_set, w_set.
void append_velocity_windows(const FusionInput& in, int window, double previous_noise_v,
                             double previous_noise_w, std::uint64_t seed, SequenceSet* v_set,
                             SequenceSet* w_set, LearnedTarget target = LearnedTarget::velocity);

// Trains both nets on the tracks (each split 70/30 chronologically, or whole
// recordings held out: LearnedValidation). A
// correction net whose free-running validation MAE is not below the kinematic
// odometry's is zeroed (model.v/w_beats_kinematic false). Throws
// std::invalid_argument (one line) when a track has no ground truth, fewer
// than 2 tracks are given for validation on recordings, the
// tracks' ticks_per_rev differ or there are too few windows.
LearnedOdometryModel train_learned_odometry(const std::vector<const FusionInput*>& tracks,
                                            const LearnedTrainingOptions& options,
                                            LearnedTrainingSummary* summary);

// Runs the nets step by step: keeps the last `window` feature rows. Steps
// before the window is full return the nominal kinematic velocities.
class LearnedOdometryStepper {
 public:
  explicit LearnedOdometryStepper(const LearnedOdometryModel* model);
  // Step k's increments and the previous (V, W) to feed back; returns (V, W).
  std::array<double, 2> step(double dticks_l, double dticks_r, double v_kin, double w_kin, double previous_v,
                             double previous_w);
  const LearnedOdometryModel& model() const { return *model_; }
  // The raw feature rows of the last step's windows (window × 3, oldest
  // first) and whether the window is full: a retraining sample (§4.2).
  const std::vector<double>& v_window() const { return v_rows_; }
  const std::vector<double>& w_window() const { return w_rows_; }
  bool ready() const { return filled_ >= model_->v_net.window; }

 private:
  const LearnedOdometryModel* model_;
  std::vector<double> v_rows_, w_rows_;  // ring of window × 3 raw features, oldest first
  int filled_ = 0;
};

// The learned odometry over a whole track, feeding back its own outputs.
// v, w per step (step 0: 0).
struct OdometrySeries {
  std::vector<double> v, w;
};
OdometrySeries run_learned_odometry(const FusionInput& in, const LearnedOdometryModel& model);
OdometrySeries kinematic_odometry(const FusionInput& in);

}  // namespace odotune

// Learned odometry (Fariña, Acosta, Toledo & Acosta, "Improving Odometric
// Model Performance Based on LSTM Networks", Sensors 2023, 23, 961,
// ../shared/papers/002_*.txt, §4 and Fig. 4): two LSTMs, one for V and one
// for W, each seeing a window of steps (10 Hz) of features, standardised
// (eq. 4), one layer, linear output.
//
// Two kinds of nets (LearnedTarget):
//  - the paper's (velocity): the nets output V and W from the encoder
//    increments and the previous velocity, (Δct_r, Δct_l, previous V) resp.
//    (…, previous W), 5 units, 20 steps, trained with a robust (≈ MAE) loss
//    against ground-truth velocities on 70 % of the windows (chronological
//    split per track). "Previous velocity": in training the ground truth of
//    the previous step (teacher forcing); when running, the net's own
//    previous output, or the fusion filter's estimate (learned_fusion.h).
//  - correction nets: each outputs a correction added to the nominal
//    kinematic velocity of its track's odometry (wheels, a measured twist or
//    commands, odotune/tracks/odometry_input.h), from a zero output start, so that a
//    net that has learnt nothing is the kinematic odometry. They read the
//    odometry itself (and the gyro where the model has one), never their own
//    output: a net fed what it produced drifts on its own errors. Their
//    settings are chosen, and each is kept or dropped, by cross-validation
//    over the training recordings (odotune/learned/odometry_selection.h).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/learned/fusion_input.h>
#include <odotune/learned/lstm_training.h>
#include <odotune/learned/odometry_net.h>

namespace odotune::learned {

enum class LearnedTarget { velocity, correction };
std::string_view to_string(LearnedTarget t);  // "velocity", "correction"
bool parse_learned_target(std::string_view text, LearnedTarget* out);

// What the nets are validated on. For the paper's nets: the last (1 −
// train_fraction) of each track's steps (chronological, the paper's split)
// or the last max(1, round(N·(1 − train_fraction))) of the N tracks as given,
// held out whole (recordings). For correction nets: the units of the
// cross-validation (odometry_selection.h), whole recordings or time blocks.
enum class LearnedValidation { chronological, recordings, blocks };
std::string_view to_string(LearnedValidation v);  // "chronological", "recordings", "blocks"
bool parse_learned_validation(std::string_view text, LearnedValidation* out);

// The three features a net reads per step (OdometryNet::kInputs), by layout:
//   paper    (Δct_r, Δct_l, previous V)  resp. (Δct_r, Δct_l, previous W)
//   channel  V net (v_kin, 0, 0);  W net (w_kin, gyro_z or 0, 0)
//   both     (v_kin, w_kin, gyro_z or 0) for either net
// with v_kin, w_kin the nominal kinematic odometry (FusionInput) and gyro_z
// the step's yaw rate, 0 for a model without a gyro. A constant 0 is
// standardised to 0 and adds nothing. `channel` gives each net its own
// channel of the odometry: a drive controller tracks v and ω each by its
// own loop, so what carries from one robot to another is how each
// channel follows; `both` also lets ω depend on v (what unequal wheels
// do on one robot).
enum class LearnedFeatures { paper, channel, both };
std::string_view to_string(LearnedFeatures f);  // "paper", "channel", "both"
bool parse_learned_features(std::string_view text, LearnedFeatures* out);
enum LearnedFeature : int { kFeatDticksR = 0, kFeatDticksL = 1, kFeatPrevious = 2 };  // the paper's layout

struct LearnedOdometryModel {
  OdometryNet v_net, w_net;
  double rate_hz = 10.0;  // the step rate the nets were trained at
  // Of the robot they were trained on (increments are in counts); wheel
  // input only (0 otherwise).
  double ticks_per_rev = 0.0;
  LearnedTarget target = LearnedTarget::velocity;               // what the nets output (see the file comment)
  tracks::OdometryInput input = tracks::OdometryInput::wheels;  // the odometry they read
  LearnedFeatures features = LearnedFeatures::paper;
  bool gyro = false;  // the features hold gyro_z: a track must have a gyro
  // A correction net that did not beat the kinematic odometry in its
  // validation is zeroed (it outputs the kinematics) and flagged false here;
  // always true for velocity nets.
  bool v_beats_kinematic = true, w_beats_kinematic = true;
  // Validation MAE of each net at training time [m/s, rad/s] (the static
  // odometry variance falls back on it when there is no slip detector).
  double v_validation_mae = 0.0, w_validation_mae = 0.0;
  // The kinematic odometry's MAE on the same validation [m/s, rad/s] (for
  // its variance in a fusion); 0 when unknown (files written before it).
  double v_kinematic_mae = 0.0, w_kinematic_mae = 0.0;
  // Nets of one size and window; features consistent with target and input
  // (paper: velocity nets on wheels; else a correction); positive rate (and
  // ticks_per_rev for wheels).
  bool IsValid(std::string* why) const;
};

// The raw features of step k of `in` for the V net (which = 0) or the W net
// (1) into row[0..3): `gyro_z` is the step's yaw rate [rad/s] (0 for a model
// without a gyro), `previous` the previous velocity of the paper's layout
// (ignored by the others). NaN where the step lacks a value.
void feature_row(const FusionInput& in, std::size_t k, LearnedFeatures features, double gyro_z, int which,
                 double previous, double* row);

// Steps [first, end) of track `track`: a recording or a time block, the unit
// validation holds out.
struct StepSpan {
  std::size_t track = 0, first = 0, end = 0;
};

// What a set of windows is cut for.
struct WindowSpec {
  int window = 20;  // steps
  LearnedFeatures features = LearnedFeatures::paper;
  bool gyro = false;
  LearnedTarget target = LearnedTarget::velocity;
  // The paper's layout: σ of the noise on the teacher-forced previous V and
  // W [m/s, rad/s], drawn from `seed` (0 = pure teacher forcing).
  double previous_noise_v = 0.0, previous_noise_w = 0.0;
  std::uint64_t seed = 1;
};

// The windows of steps [first, end) of one track: every step k whose whole
// window (and, for the paper's layout, the truth of the step before it) lies
// in the span and is finite, with ground truth at k; target v_true[k] (resp.
// w_true[k]), less v_kin[k] (w_kin[k]) for a correction. Appends to v_set,
// w_set (window and inputs set by the caller).
void append_velocity_windows(const FusionInput& in, const WindowSpec& spec, std::size_t first, std::size_t end,
                             SequenceSet* v_set, SequenceSet* w_set);
// The whole track.
inline void append_velocity_windows(const FusionInput& in, const WindowSpec& spec, SequenceSet* v_set,
                                    SequenceSet* w_set) {
  append_velocity_windows(in, spec, 0, in.size(), v_set, w_set);
}

// The paper's nets (target velocity: LearnedTrainingOptions below).
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
  // it) over the validation steps. LM from one random start is unreliable on
  // these nets: on wheelchair_learn with seeds 1-5 the validation MAE of a
  // single start ranged over two decades (V 0.0016-0.21 m/s, W
  // 0.0028-0.12 rad/s), the bad starts far worse than the kinematic model;
  // and a small one-step (teacher-forced) validation MAE did not guarantee a
  // net that stays on track on its own outputs.
  int restarts = 4;
  LearnedValidation validation = LearnedValidation::chronological;  // chronological or recordings
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

// Trains the paper's nets on the tracks (each split 70/30 chronologically, or
// whole recordings held out: LearnedValidation). Throws
// std::invalid_argument (one line) when a track has no ground truth or no
// wheel odometry, fewer than 2 tracks are given for validation on
// recordings, the tracks' ticks_per_rev differ or there are too few windows.
LearnedOdometryModel train_learned_odometry(const std::vector<const FusionInput*>& tracks,
                                            const LearnedTrainingOptions& options,
                                            LearnedTrainingSummary* summary);

// Checks that `in` carries what `model` reads: the same odometry source
// (and robot, by ticks_per_rev, for wheels) and a gyro when the model has
// one. Returns false with *why one line naming the track.
bool model_fits(const LearnedOdometryModel& model, const FusionInput& in, std::string* why);

// Runs the nets step by step: keeps the last `window` feature rows. Steps
// before the window is full return the nominal kinematic velocities. A step
// without a gyro sample repeats the last one.
class LearnedOdometryStepper {
 public:
  explicit LearnedOdometryStepper(const LearnedOdometryModel* model);
  // Step k of `in` and the previous (V, W) to feed back (the paper's
  // layout); returns (V, W).
  std::array<double, 2> step(const FusionInput& in, std::size_t k, double previous_v, double previous_w);
  const LearnedOdometryModel& model() const { return *model_; }
  // The raw feature rows of the last step's windows (window × 3, oldest
  // first) and whether the window is full: a retraining sample (§4.2).
  const std::vector<double>& v_window() const { return v_rows_; }
  const std::vector<double>& w_window() const { return w_rows_; }
  bool ready() const { return filled_ >= model_->v_net.window(); }

 private:
  const LearnedOdometryModel* model_;
  std::vector<double> v_rows_, w_rows_;  // window × 3 raw features, oldest first
  double last_gyro_ = 0.0;               // the last finite gyro_z [rad/s]
  int filled_ = 0;
};

// The learned odometry over steps [first, end) of a track (the whole track by
// default), feeding back its own outputs; v, w per step of the track (0
// outside the span and at its first step).
struct OdometrySeries {
  std::vector<double> v, w;
};
OdometrySeries run_learned_odometry(const FusionInput& in, const LearnedOdometryModel& model,
                                    std::size_t first = 0, std::size_t end = static_cast<std::size_t>(-1));
OdometrySeries kinematic_odometry(const FusionInput& in);

}  // namespace odotune::learned

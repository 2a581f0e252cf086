// Correction nets (odotune/learned/learned_odometry.h) whose settings are chosen by
// cross-validation inside the training recordings, and which are kept only
// where they beat the kinematic odometry on data they never saw.
//
// Units and folds. The training data are cut into units: whole recordings
// (LearnedValidation::recordings), or consecutive time blocks of block_s
// seconds of each recording (blocks), long enough to carry the drift of
// dead reckoning. The units are dealt round robin into at most max_folds
// folds.
//
// For each candidate setting (units × window × weight decay × features) and
// each fold, a V and a W net are trained on the windows of the other folds,
// with early stopping on the fold's windows (the nets read no output of
// their own, so their error on a window is their error running). The fold's
// measures are those of the stopped nets against the kinematic odometry:
// V MAE, W MAE, and the position RMSE of dead reckoning restarted every 10 s
// and every 60 s and over each whole unit, for the four combinations
// kinematic, V net only, W net only and both.
//
// Choice. A combination qualifies when, on every fold, each net it uses has
// a lower MAE than the kinematic odometry, its whole-unit position RMSE is
// no larger, and its mean score over the folds, the mean of ln(RMSE ratio)
// over the three position measures, is below 0. Among the qualifying
// (candidate, combination) pairs, the one-standard-error rule (Hastie,
// Tibshirani & Friedman, The Elements of Statistical Learning, 2nd ed.,
// §7.10): take the best mean score and its standard error over the folds;
// chosen is the simplest candidate whose score is within one standard error
// of it (simplest: channel before both, fewer units, a shorter window, a
// larger decay, in that order), with its best qualifying combination. A
// handful of folds cannot tell close candidates apart, and the simpler one
// carries to new recordings more often. When nothing qualifies, the model is
// the kinematic odometry (both nets zeroed and flagged as not beating it).
//
// The model. The chosen setting is trained on every unit, each net for the
// median over the folds of its early-stopping iteration. The nets the
// combination leaves out are zeroed (LearnedOdometryModel::v/w_beats_kinematic
// false). Its validation figures are the folds'.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include <odotune/learned/learned_odometry.h>

namespace odotune::learned {

struct CorrectionSettings {
  int units = 5;              // LSTM units (kOdometryNetUnits)
  int window = 20;            // steps
  double weight_decay = 0.0;  // L2 λ on the weights, standardised units (LstmTrainingOptions)
  LearnedFeatures features = LearnedFeatures::channel;
  std::string label() const;  // e.g. "5 units, 20 steps, decay 0, channel"
};

// The four ways to combine the nets with the kinematic odometry.
enum class NetCombination : int { kinematic = 0, v_net = 1, w_net = 2, both = 3 };
inline constexpr int kNetCombinations = 4;
std::string_view to_string(NetCombination c);  // "kinematic", "V net", "W net", "V and W nets"

struct SelectionOptions {
  // Each fit: max_iterations is the cap, early_stopping_patience the
  // patience (> 0), seed the initial weights of every fit, num_threads.
  LstmTrainingOptions training = [] {
    LstmTrainingOptions t;
    t.early_stopping_patience = 5;
    return t;
  }();
  LearnedValidation validation = LearnedValidation::recordings;  // recordings or blocks
  double block_s = 120.0;                                        // blocks' length [s], ≥ 10 × the window
  int max_folds = 5;                                             // ≥ 2
  std::vector<int> units{3, 5};
  std::vector<int> windows{10, 20};
  std::vector<double> weight_decays{0.0, 10.0};
  std::vector<LearnedFeatures> features{LearnedFeatures::channel, LearnedFeatures::both};
  bool use_gyro = true;  // read the gyro when every track has one
  bool IsValid(std::string* why) const;
};

// One fold's measures of a candidate: MAEs [m/s, rad/s] of the kinematic
// odometry (index 0) and the nets (1); position RMSEs [m] per combination
// (NetCombination order) over 10-s and 60-s windows and whole units.
struct FoldMeasures {
  std::vector<std::string> units;  // the fold's units, e.g. "mrclam7-robot1" or "litw 0-120 s"
  std::array<double, 2> v_mae{}, w_mae{};
  std::array<std::array<double, 3>, kNetCombinations> pose_rmse{};  // [combination][10 s, 60 s, unit]
  int v_iteration = 0, w_iteration = 0;                             // early stopping's
};

struct CandidateResult {
  CorrectionSettings settings;
  std::vector<FoldMeasures> folds;
  // Per combination: each fold's score (the mean of ln(pose RMSE ÷
  // kinematic's) over the three position measures), their mean and its
  // standard error (sd / √folds).
  std::array<std::vector<double>, kNetCombinations> fold_scores;
  std::array<double, kNetCombinations> score{}, score_se{};
  std::array<bool, kNetCombinations> qualifies{};
};

struct SelectionSummary {
  std::vector<std::string> units;  // every unit, in order
  int folds = 0;
  bool gyro = false;
  std::vector<CandidateResult> candidates;
  std::size_t chosen = 0;  // candidates[chosen]: the chosen setting (the best score when none qualifies)
  NetCombination combination = NetCombination::kinematic;
  int v_iterations = 0, w_iterations = 0;  // the final training's
  LstmTrainingSummary v, w;                // the final training's
  std::size_t train_windows = 0;
  double seconds = 0.0;
};

// The scores, standard errors and gates of each combination of a candidate
// (the header's "Choice") from its folds' measures.
void score_candidate(CandidateResult& r);
// The one-standard-error choice among s.candidates (scored) into s.chosen
// and s.combination; the best-scoring candidate, with the kinematic
// combination, when nothing qualifies.
void choose_candidate(SelectionSummary& s);

// Progress: fits done of total (candidates × folds, then 1 for the final).
using SelectionProgress = std::function<void(long done, long total)>;

// Throws std::invalid_argument (one line) for invalid options, a track
// without ground truth, tracks of different odometry sources, rates or
// robots, fewer than 2 units, or a fold with too few windows to train on.
LearnedOdometryModel train_correction_odometry(const std::vector<const FusionInput*>& tracks,
                                               const SelectionOptions& options, SelectionSummary* summary,
                                               const SelectionProgress& progress = {});

}  // namespace odotune::learned

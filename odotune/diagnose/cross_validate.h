// Time-block cross-validation of effect sets, the machinery of the model
// selection (select.h; docs/diagnosis-design.md step 7).
//
// Windows: make_windows(in, fit.window_s). Folds: K = min(folds, #windows)
// contiguous blocks of windows (window w in fold floor(w*K/#windows)), or,
// for several recordings laid end to end, one fold per recording.
//
// Errors are NORMALISED: per reference sample
//   (dx^2 + dy^2)/sigma_m^2 (+ dtheta^2/sigma_rad^2 with a reference heading
//   and fit.use_heading), sigma = DiagInput::ref_sigma_*,
// so reference noise alone scores about 2 (3 with heading) per sample.
//
// Fits are fit_effects() calls (counted in fits()) without standard errors
// (FitOptions::standard_errors off: the search reads costs and values);
// fits and replays reuse one EffectModel per combination of active effects
// (building a model costs far more than replaying it, and a model replays
// any parameter values).
//
// Threads. fit(), model_for(), cross_validate(), fit_all() and own_noop()
// may be called from several threads at once (the model cache is locked,
// the fit count atomic, a built model is read only); cross_validate_all
// runs its fold fits in parallel with OpenMP. Every fit is single-threaded
// and deterministic, so results do not depend on the number of threads.
// Windows are anchored as fit_anchoring(in, fit) says (window_replay.h).
#pragma once

#include <atomic>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/fit.h>
#include <odotune/diagnose/paired_test.h>
#include <odotune/diagnose/window_replay.h>

namespace odotune::diagnose {

// Predictions per reference sample (NaN where not predicted).
struct SamplePred {
  std::vector<double> x_m, y_m, theta_rad;
};

// An effect set evaluated on every window: held-out predictions
// (cross_validate) or in-sample ones (fit_all).
struct SetEval {
  bool ok = false;
  std::string error;  // why not ok (a fit threw, non-finite errors)
  SamplePred pred;
  std::vector<double> window_sse;                   // normalised SSE per window
  double score = 0.0;                               // pooled normalised MSE per sample
  double pos_rmse_m = 0.0, heading_rmse_rad = 0.0;  // pooled (heading NaN without)
  std::vector<EffectSet> folds;                     // cross_validate: the fitted set of each fold
  EffectSet fitted;                                 // fit_all: the fitted set
  double cost = 0.0;                                // fit_all: fit_effects' final cost (NaN for the empty set)
  double bic = 0.0;                                 // fit_all (see fit_all)
};

// A thinned, denoised copy of a reference for cross-validation: every
// stride-th reference sample (stride = floor(reference rate / rate_hz);
// returns 1 and leaves `out` untouched when that is 1, rate_hz is 0, the
// reference is mixed (DiagInput::ref_w non-empty) or the
// reference has fewer than 3 samples), each kept position replaced by a
// local quadratic least-squares fit of the reference over +-half_s (its bias
// at a step change of acceleration a is at most ~0.011 a h^2: 0.3 mm for
// 0.5 m/s^2 and h = 0.25 s), each kept heading by a trend that turns with
// the robot (the integrated gyro; without a gyro the nominal odometry heading
// (S_r - S_l)/D of `model`) plus a local quadratic fit of (reference -
// trend) over +-heading_half_s (the difference is smooth where the turns are
// not: smoothing the heading itself over 1 s would err by up to
// 0.011 alpha h^2 = 25 mrad at a 2.5 rad/s^2 turn-rate ramp; the odometry
// trend is itself late under time_offset, the gyro is not), and the
// reference sigmas scaled by the median noise factor sqrt(e0'(X'X)^-1 e0) of
// those fits (floored like build_diag_input's: 1 mm, 1 mrad). Returns the
// stride; `correlated` = kept samples per (the longer) smoothing span, >= 1:
// the correlated_samples to give a CrossValidator on `out`.
int denoised_reference(const DiagInput& in, double rate_hz, double half_s, double heading_half_s,
                       const ModelOptions& model, DiagInput& out, double& correlated);

// `structure` with the fitted parameters of the effects `warm` has on taken
// from `warm` (discrete parameters and the other effects from `structure`).
EffectSet start_from(const EffectSet& structure, const EffectSet& warm);

class CrossValidator {
 public:
  // `in` must outlive the validator. Throws std::invalid_argument for
  // invalid fit options, folds < 2, or an input make_windows rejects.
  // correlated_samples (>= 1): how many consecutive reference samples share
  // their noise (a smoothed reference); the white-noise law of compare()
  // counts that many samples as one.
  // recording_starts_s (ascending pooled start times of recordings laid end
  // to end): with two or more, fold f holds the windows anchored in
  // recording f (leave one recording out; recordings without a window are
  // dropped), unless fewer than two folds would have windows; then `folds`
  // blocks as above.
  CrossValidator(const DiagInput& in, const FitOptions& fit, int folds, double correlated_samples = 1.0,
                 const std::vector<double>& recording_starts_s = {});
  // The windows fold f is tested on (indices into windows()).
  const std::vector<int>& fold_windows(int f) const { return test_.at(static_cast<std::size_t>(f)); }
  // True when the folds are recordings (above).
  bool folds_are_recordings() const { return by_recording_; }

  const DiagInput& input() const { return *in_; }
  const std::vector<Window>& windows() const { return windows_; }
  int num_folds() const { return static_cast<int>(test_.size()); }
  std::size_t num_samples() const { return n_samples_; }
  int fits() const { return fits_.load(); }

  // fit_effects on `train` (empty = all windows) with max_iterations.
  FitSummary fit(const EffectSet& start, const std::vector<int>& train, int max_iterations);
  // A screening fit of `trial` alone beside the other effects of `start`
  // (held at their values) on `windows` (empty = all).
  FitSummary screen(const EffectSet& start, Effect trial, const std::vector<int>& windows, int max_iterations);
  // Per window (index order), the fit cost of `at` with the window's anchor
  // fitted alone (FitSummary::settled_window_costs; 0 for a window a fit
  // skips). A screening fit's final cost minus the sum of these over its
  // fitted windows, with `at` = its start with the trial at no-op, is what
  // the trial removes there, comparable between trials over other windows.
  std::vector<double> settled_costs(const EffectSet& at, Effect trial);

  // The cached model of `set`'s active effects (built on first use).
  const EffectModel& model_for(const EffectSet& set);

  // Each fold fitted on the other folds (warm-started from warm[f], the same
  // fold's fit of a smaller set, when warm is not empty; the empty set is
  // replayed as it is) and replayed on its own windows. Fit errors are
  // caught: ok = false with the message.
  SetEval cross_validate(const EffectSet& structure, const std::vector<EffectSet>& warm, int max_iterations);

  // cross_validate of each set (same warm for all), the (set, fold) fits run
  // in parallel (OpenMP): the same results as one call per set in turn, for
  // any number of threads.
  std::vector<SetEval> cross_validate_all(const std::vector<EffectSet>& structures,
                                          const std::vector<EffectSet>& warm, int max_iterations);

  // Fitted on all windows from start_from(structure, warm), replayed on all.
  // bic = n ln(RSS/n) + p ln(n): n scored samples, RSS the normalised SSE,
  // p = fitted parameters + discrete ones (radius_step.t 1, slip_zone box 4)
  // + 3 per window with free anchors (fit_anchoring).
  SetEval fit_all(const EffectSet& structure, const EffectSet& warm, int max_iterations);

  // `cv` replayed with effect e's fitted parameters at their no-op values in
  // every fold (no refit): what the effect itself adds to its set (its
  // `folds` hold those sets).
  SetEval own_noop(const SetEval& cv, Effect e);

  // The held-out predictions of `cv` as a user's dead reckoning sees them:
  // each fold's fitted set replayed on the fold's own windows with the
  // replay's own anchors (window_replay.h: on the reference pose at the
  // window's start when the reference has a heading, else the closed-form
  // rigid alignment), position and heading RMSE pooled over every window's
  // scored samples (heading NaN without a reference heading). A `cv`
  // without fold sets (the nominal model) is the empty set in every fold.
  // The measure of the selection's materiality rule, the same as the benchmark's truth.
  struct Replayed {
    double pos_rmse_m = std::numeric_limits<double>::quiet_NaN();
    double heading_rmse_rad = std::numeric_limits<double>::quiet_NaN();
  };
  Replayed replayed(const SetEval& cv);

  // `alt` against `ref`, window by window: paired_windows (paired_test.h)
  // over every window's normalised SSEs and prediction change, with
  // L = correlated_samples; gain and rel from the pooled scores.
  PairedComparison compare(const SetEval& ref, const SetEval& alt, double alpha) const;

 private:
  void predict(const EffectSet& set, const std::vector<int>& which, SamplePred& p);
  SamplePred empty_pred() const;
  void finish(SetEval& e) const;

  const DiagInput* in_;
  FitOptions fit_;
  double corr_ = 1.0;
  std::vector<Window> windows_;
  std::vector<std::vector<int>> train_, test_;  // per fold
  bool heading_ = false;
  bool by_recording_ = false;
  double ism_ = 1.0, ish_ = 0.0;  // inverse reference sigmas
  int comps_ = 2;                 // error components per sample
  std::size_t n_samples_ = 0;
  std::atomic<int> fits_{0};
  std::mutex models_mutex_;  // guards models_ (model_for from several threads)
  std::map<std::string, std::unique_ptr<EffectModel>> models_;
};

}  // namespace odotune::diagnose

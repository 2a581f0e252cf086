// Least-squares fit of a set of physics effects on a set of replay windows
// (docs/diagnosis-design.md step 4), with Ceres.
//
// Problem. One residual block per training window (window_replay.h): for every
// scored reference sample, (predicted - reference) position / ref_sigma_m per
// axis, plus (predicted - reference) heading / ref_sigma_rad when the
// reference has heading and use_heading is on. Free parameters: the `fitted`
// slots of param_layout(which) (radius_step.t, the slip_zone box and gyro
// parameters stay at the values `which` holds), bounded by the effect table's
// ranges; with free anchors (window_replay.h: fixes, ground truth without
// heading, or any reference with free_anchor_with_heading) also one anchor
// pose (x0, y0, theta0) per window, started at the closed-form alignment of
// window_replay.h. Training windows of a free-anchor reference without
// heading whose nominal positions spread (RMS distance from their centroid)
// less than min_spread_sigmas*ref_sigma_m are left out: their anchor heading
// is unobservable (listed in FitSummary::skipped_windows).
//
// Robust loss. Applied per residual r (already in sigmas) inside the cost:
// r -> sign(r)*sqrt(rho(r^2)), rho = Huber or Cauchy with scale loss_scale,
// so one bad reference sample is down-weighted without discarding its window.
//
// Uncertainty. ceres::Covariance (dense SVD) at the solution, scaled by the
// residual variance factor s^2 = 2*final_cost/(m - n) (m residuals, n free
// parameters including anchors), since dead-reckoning residuals are not the
// reference noise alone. A rank-deficient Jacobian (an effect the data cannot
// see, e.g. a slip zone never entered) gives NaN standard errors and
// rank_deficient = true. Dead-reckoning residuals within a window are
// correlated, so the standard errors are optimistic; held-out windows, not
// standard errors, are the proof that a fit helps.
//
// Scores. Before = the model with `which`'s starting values (normally the
// no-op values, i.e. nominal kinematics); after = the fitted model; both
// replayed with replay() (closed-form anchors for free anchors), on the
// training windows and on the held-out windows.
//
// Speed. Building the EffectModel (the nominal rim travel and accelerations
// of every odometry node) costs more than a short fit; callers that fit one
// structure many times (cross_validate.h) pass a prebuilt model. With free
// anchors, a window is dead-reckoned in a local frame with derivatives by
// the effect parameters only and composed with its anchor analytically
// (a rigid motion), and the anchors, each meeting only its own window's
// residuals, are eliminated by a Schur complement (DENSE_SCHUR): a dense QR
// of the whole Jacobian would cost rows x (3 windows)^2. Cost-only
// evaluations (trial steps) replay in doubles, and a window remembers its
// last one (Ceres' projected line search and the minimizer evaluate the same
// trial point); the line search interpolates quadratically, so it needs no
// Jacobian. Standard errors (a dense SVD over effect and anchor parameters,
// rows x (3 windows)^2, i.e. quadratic in the track's length) are skipped
// when FitOptions::standard_errors is off (the model search's fits).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/window_replay.h>

namespace odotune::diagnose {

enum class RobustLoss { none, huber, cauchy };

struct FitOptions {
  double window_s = 20.0;  // replay window [s]; 0 = the whole track as one window
  RobustLoss loss = RobustLoss::huber;
  double loss_scale = 3.0;         // where the loss turns robust [reference sigmas]
  bool use_heading = true;         // heading residuals when the reference has heading
  int max_iterations = 100;        // Levenberg-Marquardt iterations
  double min_spread_sigmas = 2.0;  // free-anchor windows that move less are not fitted
  // Fit each window's anchor also when the reference has heading (ground
  // truth): the anchor is then a nuisance pose, not one noisy sample
  // (window_replay.h). Off by default here; the model selection turns it on.
  bool free_anchor_with_heading = false;
  // Standard errors (ceres::Covariance and the rank check, which cost about
  // two Jacobian evaluations and a dense SVD per fit). Off for the fits of
  // the model search, which read the cost and the values only: std_error is
  // then NaN and rank_deficient false.
  bool standard_errors = true;
  // Effects whose parameters the fit holds at their starting values (the
  // search's screening fits of one new effect beside a fitted set).
  std::vector<Effect> held_effects;
  // Free anchors only: before the fit, each window's anchor is fitted alone
  // with the parameters at their starting values (FitSummary::
  // settled_window_costs): the start's cost per window at its best anchor.
  bool settle_anchors = false;
  // FitSummary's "before" scores at these values (the same structure)
  // instead of the starting values: a fit warm-started from an earlier fit
  // still reports nominal -> fitted.
  std::optional<EffectSet> score_before_at;
  ModelOptions model;
  bool IsValid(std::string* why) const;
};

struct FitParam {
  std::string name;        // "effect.param" (param_layout)
  double initial = 0.0;    // starting value (clamped into the bounds)
  double value = 0.0;      // fitted value (= initial when not fitted)
  double std_error = 0.0;  // standard error; NaN when not fitted or rank deficient
  bool fitted = false;     // false: held fixed (see param_layout, FitOptions::held_effects)
  bool at_bound = false;   // the fitted value sits on a bound of its range
};

struct WindowScore {
  int window = 0;
  double before_pos_rmse_m = 0.0, after_pos_rmse_m = 0.0;
  double before_heading_rmse_rad = 0.0, after_heading_rmse_rad = 0.0;  // NaN without heading
};

struct SetScore {
  std::vector<WindowScore> windows;
  double before_pos_rmse_m = 0.0, after_pos_rmse_m = 0.0;  // pooled; NaN for no window
  double before_heading_rmse_rad = 0.0, after_heading_rmse_rad = 0.0;
};

struct FitSummary {
  EffectSet effects;             // `which` with the fitted values
  std::vector<FitParam> params;  // layout order
  bool converged = false;        // Ceres reported convergence
  bool rank_deficient = false;   // covariance unavailable (see file comment)
  std::string termination;       // Ceres' one-line report
  int iterations = 0;
  double initial_cost = 0.0, final_cost = 0.0;  // Ceres costs (1/2 sum of robustified r^2)
  double residual_scale = 0.0;                  // s = sqrt(2*final_cost/(m - n))
  std::size_t num_residuals = 0;
  double solve_time_s = 0.0;
  std::vector<int> fitted_windows;    // training windows in the problem
  std::vector<int> skipped_windows;   // training windows left out (free anchor, no motion)
  std::vector<Pose<double>> anchors;  // fitted anchors of fitted_windows (free anchor only)
  // settle_anchors: per fitted window, the cost at the starting values with
  // its anchor fitted alone (1/2 sum of robustified r^2).
  std::vector<double> settled_window_costs;
  SetScore train, heldout;
};

// Fits the free parameters of `which` (its values are the starting point) on
// `train_windows` (indices of make_windows(in, options.window_s); empty = every
// window not held out) and scores train and held-out windows before/after.
// Throws std::invalid_argument (one line) for invalid options, a window index
// out of range or in both lists, or a set with no free parameter.
FitSummary fit_effects(const DiagInput& in, const EffectSet& which, const std::vector<int>& train_windows,
                       const std::vector<int>& heldout_windows, const FitOptions& options = {});

// The same with a prebuilt model: `model` must have been built for `in` with
// options.model and the same active effects as `which` (its parameter
// values do not matter); throws std::invalid_argument otherwise.
FitSummary fit_effects(const EffectModel& model, const DiagInput& in, const EffectSet& which,
                       const std::vector<int>& train_windows, const std::vector<int>& heldout_windows,
                       const FitOptions& options = {});

// The windows' anchoring a fit with `options` uses on `in` (window_replay.h).
inline Anchoring fit_anchoring(const DiagInput& in, const FitOptions& options) {
  return anchoring(in, options.free_anchor_with_heading);
}

}  // namespace odotune::diagnose

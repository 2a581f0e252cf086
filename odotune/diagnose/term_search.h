// Physics outside the list (docs/diagnosis-design.md, "Physics outside the
// list: term search"): when the chosen model of a track
// still leaves a mismatch, search a library of candidate terms
// (odotune/sim/model_terms.h: corrections of a wheel's ground speed by functions
// of v, w, their changes, |v·w|, sin/cos harmonics of each wheel's rotation
// angle, position and time) by sparse regression, choose the terms by
// cross-validated error, prove them on the held-out windows, and report them
// as a formula (the `model` of an `unexplained` finding,
// ../shared/specs/diagnosis-output.md).
//
// Model. The chosen effects (an EffectSet with fitted values; the Stepper of
// effect_model.h) give each wheel's ground travel g over an odometry
// interval; the terms add h*sum coef*basis(state) to it, the state being
// that interval's: v_X = g_X/h, v, w from them (nominal base times
// wheel_base_error), dv_X/dt = the nominal rim acceleration (OdoSeries),
// φ_X = the wheel's rotation at the interval's middle (wheel angles; for
// body-velocity odometry the nominal rim travel / radius, and no harmonic
// bases without radii), x, y = the reference position interpolated there,
// t = time since the first odometry sample. The body step is then rebuilt
// (lateral_skid's v_y from the new ds, dθ) and dead-reckoned per window as
// window_replay.h does. As the simulator (docs/simulator.md step 5a), so a
// term found replays in `odotune simulate` (model_terms.h).
//
// Residuals. Per scored reference sample of a window: (predicted −
// reference) position / ref_sigma_m per axis, and heading / ref_sigma_rad
// with a reference heading. Every window's anchor is a free nuisance pose
// (as the selection's fits, select.h): replay() chooses it in closed form at
// zero coefficients, and for other coefficients it is re-aligned by
// Gauss-Newton on the same weighted sum (a rigid motion commutes with dead
// reckoning; slip_zone's inside test is not redone).
//
// Search. The library's columns J (derivatives of the aligned residuals by
// each coefficient, forward differences at zero, the anchors projected out
// per window) make the problem linear: r(c) ≈ r0 + J c. Forward stepwise
// selection (sparse regression with a greedy support): at each step every
// remaining term is added to the support and scored by K-fold time-block
// cross-validation over the TRAINING windows (least squares on K−1 folds,
// squared error on the other, from per-window normal equations, so a score
// costs O(terms^3) whatever the track's length); the best is accepted when
// it lowers the CV error by at least min_rel_cv_gain; stops after max_terms.
// The support is then refitted on all training windows by Gauss-Newton
// through the replay (Jacobians re-taken at the current coefficients,
// refine_iterations times); standard errors from (JᵀJ)⁻¹ scaled by the
// residual variance (optimistic, as fit.h says: dead-reckoning residuals of
// one window are correlated).
//
// Proof. Position RMSE of the aligned replay (as a finding's `fit`) without
// and with the terms on the training and the held-out windows; the model is
// found only if the held-out gain passes `floor_m` (odotune/diagnose/materiality.h,
// the caller's floor) and the CV chose at least one term. Why hand-written
// least squares instead of a Ceres problem: the anchors are eliminated in
// closed form per window and the stepwise search needs thousands of small
// fits of the same normal equations; Eigen's LDLT solves them.
//
// Cost: (library size + 1) replays of the track for the columns, plus
// (support size + 1) per refinement: linear in the track's length.
// Deterministic; no I/O.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/window_replay.h>
#include <odotune/sim/model_terms.h>

namespace odotune::diagnose {

struct TermSearchOptions {
  bool enabled = true;            // false: diagnose() never searches
  int max_terms = 4;              // support size limit
  int folds = 4;                  // CV folds over the training windows (fewer when fewer windows)
  double min_rel_cv_gain = 0.05;  // a term must lower the CV error by this share
  int refine_iterations = 2;      // Gauss-Newton passes of the final fit
  int align_iterations = 4;       // Gauss-Newton steps of each window's anchor
  double fd_rel_step = 1e-3;      // forward-difference step: this share of the mean |v_X| per column
  int harmonics = 3;              // sin/cos(kφ) for k = 1..harmonics (0..3)

  bool IsValid(std::string* why) const;
};

struct TermScore {
  double before_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();  // the chosen model
  double after_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();   // with the terms
  std::size_t samples = 0;  // replay_terms: scored reference samples
};

struct FoundTerm {
  sim::ModelTerm term;  // target, basis, coef
  std::string name;     // display name, "v_l·sin(φ_l)"
  double std_error = std::numeric_limits<double>::quiet_NaN();
};

// One forward step of the search (the log).
struct TermStep {
  int step = 0;
  std::string added;      // "v_l: v_l·sin(φ_l)"; "" for the empty support
  double cv_score = 0.0;  // pooled held-out squared error per residual (in sigmas^2)
  bool accepted = false;
};

struct TermModel {
  std::vector<FoundTerm> terms;  // in the order the search added them
  std::string formula;           // sim::term_formula of the terms
  std::string conditions;        // in words: "periodic in the left wheel's angle, once per turn"
  TermScore train, heldout;
  // Recordings the fit never saw (recordings.h), pooled, when there are any;
  // `proven` is false when the terms do not lower their error by the floor.
  std::optional<TermScore> other_recordings;
  bool proven = true;
};

struct TermSearchResult {
  bool found = false;           // terms chosen and materially better on held-out windows
  TermModel model;              // the fitted support (also when not found, for the log)
  std::vector<TermStep> steps;  // forward path
  int library_size = 0;         // candidate columns searched
  double floor_m = 0.0;         // the materiality floor applied
  std::string reason;           // why nothing was found ("" when found)
};

// Searches terms on top of `model` (the chosen wheel effects with their
// values; gyro effects are ignored) for the track `in` cut into `windows`
// (make_windows), with the training and held-out window lists, and the
// materiality floor `floor_m` [m] of the held-out position gain. Throws
// std::invalid_argument (one line) for invalid options, an empty training
// list or a window index out of range.
TermSearchResult search_terms(const DiagInput& in, const EffectSet& model, const std::vector<Window>& windows,
                              const std::vector<int>& train, const std::vector<int>& heldout, double floor_m,
                              const TermSearchOptions& options = {});

// Position RMSE of `in`'s windows of window_s (anchored as a finding's fit)
// with the chosen model without and with `terms` (found on another
// recording of the robot): the proof of a term model elsewhere.
TermScore replay_terms(const DiagInput& in, const EffectSet& model, const std::vector<sim::ModelTerm>& terms,
                       double window_s, const TermSearchOptions& options = {});

}  // namespace odotune::diagnose

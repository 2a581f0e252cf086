// Model selection of the diagnosis (docs/diagnosis-design.md, step 7 and
// "Model selection"): which wheel-odometry effects of
// ../shared/specs/physics-effects.md a track needs, by greedy forward
// selection with cross-validation (cross_validate.h), pairs, swaps, a
// backward pass, and a final fit whose held-out scores prove the gain. A
// candidate is accepted by the rules named in SelectOptions and defined in
// that section: size, paired test, BIC, own parameters, materiality.
// Deterministic for any number of threads (each parallel fit starts from
// values fixed before its batch); logs are data (Selection::records).
#pragma once

#include <string>
#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/fit.h>
#include <odotune/diagnose/materiality.h>
#include <odotune/diagnose/zone_boxes.h>

namespace odotune::diagnose {

// FitOptions of the selection: free anchors also with ground truth (header comment).
inline FitOptions default_select_fit() {
  FitOptions f;
  f.free_anchor_with_heading = true;
  return f;
}

struct SelectOptions {
  // window_s (> 0 here), loss, model, anchoring; max_iterations: final fits
  FitOptions fit = default_select_fit();
  std::vector<Effect> candidates;  // empty = every wheel-odometry effect (header comment)
  int folds = 5;                   // K contiguous folds of windows (fewer with fewer windows)
  // Several recordings laid end to end (recordings.h): each one's start in
  // pooled time [s], ascending. With two or more, the folds are the
  // recordings (leave one recording out) instead of `folds` blocks.
  std::vector<double> recording_starts_s;
  int max_effects = 3;                // forward steps at most
  double alpha = 1e-3;                // one-sided level of the paired test (the paired-test rule)
  double min_rel_improvement = 0.05;  // relative CV improvement needed
  double min_gain = 0.05;             // absolute CV improvement needed [normalised units/sample]
  double heldout_fraction = 0.3;      // final model: share of windows held out
  int cv_max_iterations = 50;         // Levenberg-Marquardt iterations of a CV fold fit
  int profile_max_iterations = 20;    // of a fit of the radius_step / slip_zone searches
  // Windows of a reference without heading (fixes; free anchors) are
  // lengthened to hold at least this many reference samples, but to no more
  // than a third of the track (header comment, "Windows"); 0 = fit.window_s.
  double min_window_samples = 60.0;
  double select_ref_rate_hz = 10.0;    // reference thinned to about this rate for selection; 0 = all
  double smooth_half_s = 0.25;         // half span of the thinned reference's position fits [s]
  double smooth_heading_half_s = 1.0;  // of its heading fits (around a gyro/odometry trend) [s]
  bool look_alikes = true;             // the look-alike step (header comment, "Look-alikes")
  double step_head_s = 20.0;           // radius_step.t: no step this early (or in the first window) [s]
  double step_coarse_s = 0.0;          // radius_step.t coarse grid [s]; 0 = half the head (above)
  double step_fine_s = 0.5;            // radius_step.t final resolution [s]
  double zone_cell_m = 0.25;           // slip_zone grid cell [m]
  int zone_max_boxes = 3;              // boxes found from the residual growth
  double zone_min_score = 16.0;        // score a found box needs (zone_boxes.h)
  std::vector<ZoneBox> zone_boxes;     // extra candidate boxes (e.g. from locate.h)
  MaterialityOptions materiality;      // the materiality rule and the final check (materiality.h)
  int tries_per_step = 3;              // forward step: candidates judged in CV order ("Forward step")
  bool pairs = true;                   // try the condition pairs ("Pairs") when the error stays high
  double pair_above_floor = 3.0;       // ... when the CV position RMSE exceeds this many floors
  bool swaps = true;                   // try one candidate in place of two selected effects ("Swaps")

  bool IsValid(std::string* why) const;
};

// One evaluation of the search, in the order made.
struct SearchRecord {
  int step = 0;                 // forward step (1, 2, ...), backward round, 0 for the baseline
  std::string phase;            // "baseline", "forward", "backward", "pair", "swap", "look-alike"
  std::string candidate;        // effect added (forward) or removed (backward); "" for the baseline
  std::vector<Effect> effects;  // forward: the effect added; pair: the two added; backward: the one removed
  std::string set;              // the evaluated set (structure; discrete parameters shown)
  double cv_score = 0.0;        // pooled held-out normalised MSE per sample (NaN: failed)
  double cv_pos_rmse_m = 0.0, cv_heading_rmse_rad = 0.0;  // pooled held-out (heading NaN without)
  double rel_improvement = 0.0;  // forward: (cur - cand)/cur; backward: (without - with)/without
  double gain = 0.0;             // the same difference, absolute
  int windows_changed = 0, windows_improved = 0;  // informative windows (cross_validate.h)
  double p_rank = 1.0;                            // one-sided Wilcoxon signed-rank p
  double p_t = 0.0;      // smaller one-sided t-test p (window z's, log ratios; NaN: < 3 windows)
  double p_param = 0.0;  // one-sided Stouffer p (cross_validate.h compare(); NaN: not computed)
  bool significant = false;
  // BIC of the evaluated set and its change against the set it competes with
  // (forward: new - current; backward: with - without, so < 0 favours keeping);
  // 0 when not fitted on all windows (forward candidates other than the best).
  double bic = 0.0, delta_bic = 0.0;
  bool accepted = false;  // forward: added; backward: removed
  std::string reason;     // why accepted or rejected
  // Accepted forward step: the other candidates of the step that the winner
  // does not beat by the size and paired-test rules, i.e. confounded alternatives.
  std::vector<Effect> rivals;
  double time_s = 0.0;
};

struct SelectedEffect {
  Effect effect = Effect::radius_error;
  double explains = 0.0;       // share of the baseline training SSE it removes (header comment)
  std::vector<Effect> rivals;  // confounded alternatives when it was accepted (SearchRecord)
};

struct SelectTiming {
  double total_s = 0.0;     // select_effects
  double search_s = 0.0;    // forward and backward search (includes discrete_s)
  double discrete_s = 0.0;  // radius_step.t and slip_zone box searches
  double final_s = 0.0;     // final fit and explains
  int fits = 0;             // fit_effects calls
};

struct Selection {
  std::vector<SelectedEffect> effects;  // most explaining first; empty = nominal is enough
  EffectSet structure;                  // the selected effects with their discrete parameters, else no-op
  bool fitted = false;                  // final_fit is set (effects non-empty)
  FitSummary final_fit;                 // on train_windows of the selection input, scored on heldout_windows
  std::vector<int> train_windows, heldout_windows;
  std::string split;  // "last" or "interleaved" ("" when nothing was fitted)
  double window_s = 0.0;
  int num_windows = 0, folds = 0;
  bool folds_are_recordings = false;  // leave one recording out (SelectOptions::recording_starts_s)
  int ref_stride = 1;                 // thinning of the reference during selection
  double baseline_cv_score = 0.0, final_cv_score = 0.0;  // nominal and selected set (CV)
  double floor_m = 0.0;  // materiality floor of the materiality rule [m] (materiality.h; 0 before the baseline)
  double floor_rad = 0.0;  // its heading part [rad] (0 without a reference heading)
  // Nominal model, all windows, full raw input.
  double baseline_pos_rmse_m = 0.0, baseline_heading_rmse_rad = 0.0;
  std::vector<SearchRecord> records;
  SelectTiming timing;  // wall-clock seconds
  std::string note;     // e.g. why selection could not run
};

// Throws std::invalid_argument (one line) for invalid options or an input
// fit_effects cannot use. A track with fewer than 3 windows yields no
// effects and a note. Its windows are make_windows(in, selection_window_s(in,
// options)) (= Selection::window_s): callers that index them (train_windows,
// heldout_windows) must use that length, not options.fit.window_s.

// The input the selection searches and scores on ("Data" above): `in` with
// its reference thinned to about select_ref_rate_hz and denoised
// (cross_validate.h denoised_reference) when that keeps the windows of
// selection_window_s(in, options); else a copy of `in` (stride 1).
struct SelectionInput {
  DiagInput input;
  int stride = 1;           // reference thinning; 1 = the raw reference
  double correlated = 1.0;  // kept samples per smoothing span (CrossValidator)
};
SelectionInput selection_input(const DiagInput& in, const SelectOptions& options);

// The selection on `in` searched and scored on `si` = selection_input(in,
// options), built once by the caller (diagnose() scores its findings on it too).
Selection select_effects(const DiagInput& in, const SelectionInput& si, const SelectOptions& options);
// The same, building selection_input(in, options) itself.
Selection select_effects(const DiagInput& in, const SelectOptions& options = {});

// The window length select_effects uses on `in` (header comment, "Windows").
double selection_window_s(const DiagInput& in, const SelectOptions& options);

}  // namespace odotune::diagnose

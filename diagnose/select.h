// Model selection of the diagnosis (docs/diagnosis-design.md, step 7): which
// of the wheel-odometry effects of ../shared/specs/physics-effects.md a track
// needs, by greedy forward selection with time-block cross-validation
// (cross_validate.h), a backward pass, and a final fit whose held-out scores
// prove the gain.
//
// Candidates: radius_error, wheel_base_error, radius_step, speed_radius,
// lateral_skid, longitudinal_slip, slip_zone, time_offset, (only when the
// track has commands or is body_velocity) actuator_lag, and odometry_bias
// (ordered behind radius_error without a reference heading, below).
// gyro_bias/gyro_scale do not act on
// dead reckoning (sensor_checks.h judges them). odometry_bias without a
// reference heading: what tells it apart (physics-effects.md: "a robot
// standing still seems to move") is the odometry turning and creeping while
// the reference stands; a standing robot turning in place is invisible to
// position fixes, and while it drives, a constant yaw-rate offset b_w bends
// the path like a wheel differential (radius_error) does at cruise speed.
// So with fixes only it is a candidate (the random benchmark's fixes-only
// odometry biases were otherwise named radius_error), but it goes before
// radius_error in a forward step's order only when it beats radius_error
// by the size and paired-test rules below, and after the search a selected odometry_bias
// is swapped for radius_error unless the selected set beats the swapped one
// by the size, paired-test and materiality rules (record phase "swap"): when the data cannot
// tell them apart, the common effect is named (concealed case
// radius_error_and_time_offset: CV alone chose odometry_bias over the true
// radius_error). Likewise radius_step, a radius error from a time on (the
// nested model; its time is a searched parameter), goes before radius_error
// only when it beats it by the size and paired-test rules, with or without a heading.
//
// Windows. make_windows(in, W) with W = selection_window_s(in, options)
// (Selection::window_s): fit.window_s, except for a reference without
// heading (position fixes), where W = max(fit.window_s, min_window_samples
// reference periods) but at most a third of the track (so at least three
// windows). Why: each fixes window costs a free anchor (3 parameters) that
// absorbs the rigid part of whatever an effect does in it; what is left, the
// non-rigid part, grows about as n^3 in chi-square with n fixes per window
// (n samples of a drift growing with n), so 20 fixes at 1 Hz show a 0.5 %
// radius error by ~0.1 sigma^2 per sample, 60 fixes by ~2.5. With 60 fixes
// the 3 anchor parameters take 2.5 % of a window's 2n residuals.
//
// Anchors. Every window's anchor is a nuisance pose (fit.free_anchor_with_
// heading, on by default here: default_select_fit()), ground truth
// included: an anchor on one reference pose carries that sample's noise
// into the whole window and a fit turns it into effects (window_replay.h).
//
// Data. The search and the
// final fit run on the "selection input": the reference thinned to about
// select_ref_rate_hz and denoised by local quadratic fits over
// +-smooth_half_s (positions) and +-smooth_heading_half_s (heading, around a
// gyro or odometry trend), see denoised_reference() in cross_validate.h;
// dead reckoning still steps every odometry node. Ten times fewer residuals
// make every fit faster; the smoothing lowers the reference noise the
// paired tests see (and the thinned samples' correlation is accounted for,
// see CrossValidator).
// (Without the thinning, when it would change the windows, the raw input.)
// Errors are normalised by the reference sigmas (cross_validate.h):
// reference noise alone scores about 2 per sample (3 with a heading).
//
// Cross-validation: K = min(folds, #windows) contiguous folds of windows; a
// set is fitted on K-1 folds (cv_max_iterations) and replayed on the other,
// so every window gets a held-out prediction; CV score = pooled held-out
// normalised mean squared error per sample. Fold fits are warm-started from
// the same fold's fit of the current set (never from a fit that saw the
// held-out fold); a new effect starts at its no-op values.
//
// Forward step: every remaining candidate is added to the current set S and
// cross-validated; a candidate c (in order of CV score, below) is accepted only if
//  size: the relative CV improvement is >= min_rel_improvement and the
//      absolute one >= min_gain (a mismatch far below the reference noise is
//      not physics one can see; sensor quantisation and discretisation leave
//      such consistent but tiny mismatches);
//  paired test: the paired test of CrossValidator::compare over held-out windows is
//      significant at alpha: the exact Wilcoxon signed-rank test on the
//      per-window gains, or t-tests on their z-scores and log ratios, or
//      (when every informative window improved) Stouffer's combination of
//      the z-scores, or that of all informative windows but the strongest. A rank test over n windows cannot go below 2^-n
//      (p < 1e-3 needs 10 windows, all improved), and an effect that acts in
//      a few windows only (a slip zone crossed twice, a late radius step) or
//      shows little in some windows (lateral_skid needs turns) needs the
//      magnitude-aware branches;
//  BIC: BIC of a fit on all windows (CrossValidator::fit_all) decreases;
//  own parameters: c's own parameters matter: the CV predictions with c's fitted
//      parameters reset to their no-op values must be worse by the size and paired-test rules.
//      This rejects actuator_lag on wheel odometry when tau ~ 0: its no-op
//      replays the commands instead of the encoders, which can beat the
//      encoders for reasons other than a lag.
//  materiality: c is material (materiality.h): the held-out position RMSE it removes
//      is at least max(min_gain_sigmas reference sigmas of the raw input,
//      min_gain_share of the nominal model's held-out position RMSE), or,
//      with a reference heading, the held-out heading RMSE it removes passes
//      the same floor in heading (ref_sigma_rad, nominal heading RMSE); and
//      so is what the own-parameters rule compares (c's own parameters against their
//      no-op). Held-out RMSEs here are the CV's fold fits replayed as dead
//      reckoning on their held-out windows (CrossValidator::replayed: the
//      anchor on the reference pose at the window's start with a heading),
//      what a user's dead reckoning from a known pose gains and what the
//      benchmark's truth measures; the free anchors of the fits and paired
//      tests absorb part of a drift (a
//      0.24 % one-wheel radius step cut the CV score by 89 % while removing
//      9 mm of free-anchored error under a 15 mm floor, 41 mm anchored). A
//      0.6 ms lag or a 2 ms time offset can be significant on tens of
//      thousands of samples and still change nothing a user can see.
// The candidates are judged in order of CV score, up to tries_per_step of
// them, and the first that passes every rule is accepted: a candidate that
// predicts best but cannot be proven (MRCLAM: longitudinal_slip, not
// significant) must not hide one that can (the 0.2 s command delay).
// Forward selection stops when no judged candidate passes or after
// max_effects steps. Backward pass: while |S| >= 2, each effect e is removed
// in turn (CV and fit_all of S without e) and, among those whose removal
// makes the CV score worse by less than the size rule asks or the CV position
// RMSE worse by less than the materiality rule's floor, the one whose
// removal costs least is dropped (significance is not asked again: once
// another effect changes every window, the paired test of an intermittent
// effect has little power, and a needed effect must not be dropped for it).
// Confounded pairs (speed_radius vs radius_error, longitudinal_slip vs radius_error, time_offset vs actuator_lag) are decided
// by the CV score: the best candidate of a step is the one that predicts
// held-out windows best; a proxy accepted early is dropped by the backward
// pass once the true effect explains its share. Candidates the winner does
// not beat by the size and paired-test rules are logged as its rivals: the data cannot tell
// them apart, and the diagnosis should say so.
//
// Look-alikes. On commanded velocities a time offset, a first-order
// actuator lag and acceleration-driven longitudinal slip all make the motion
// trail the command, and their combinations predict much alike. After the
// other steps, the chosen ones among them are compared with every other
// choice of those three with no more effects (cross-validated, warm-started):
// those the chosen effects do not beat by the size and paired-test rules become their
// rivals, and the one with the fewest effects replaces them when it has
// fewer (the simpler physical reading). Logged as phase "look-alike".
//
// Pairs. Greedy steps add one effect at a time; two effects that each bend
// the path the other way (longitudinal slip beside a radius error, a lag
// beside a time offset) can each fail alone and only help together. When
// the forward and backward passes end with a CV position RMSE above
// pair_above_floor times the floor of the materiality rule, and max_effects leaves room,
// the pairs the conditions point to are tried, each added to the current set
// at once: acceleration (longitudinal_slip + radius_error), speed
// (speed_radius + radius_error), velocity changes (actuator_lag +
// time_offset, time_offset + radius_error), turn rate (wheel_base_error +
// lateral_skid or + radius_error), and odometry_bias + radius_error; the best
// pair by CV score is accepted by the size, paired-test, BIC and materiality rules against the current
// set, each of its effects by the own-parameters rule; then the backward pass runs again.
// Logged as SearchRecords of phase "pair".
//
// Swaps. Greedy steps accept what predicts best at each step, and two
// accepted effects can together mimic a third that never predicted best
// alone (a constant speed offset as radius error + speed radius). After the
// forward, pair and backward passes, when two or more effects are selected,
// each candidate without a discrete parameter (not radius_step, not
// slip_zone) is tried in place of each pair of them, each fitted on all
// windows (in parallel); the lowest BIC is cross-validated, unless its
// all-window score is already worse than the selected set's by the size rule's
// share, and swapped in when the selected set does not beat it by the size
// and materiality rules (what the backward pass asks of a
// removal) and the incoming effect passes the own-parameters rule. Then the backward pass
// runs again (down to one effect: an effect accepted in a pair or swapped
// in never passed a forward step alone), and in it actuator_lag, whose
// no-op is not its absence, must still pass the own-parameters rule. Logged as
// SearchRecords of phase "swap".
//
// Discrete parameters, chosen on all windows before cross-validation (so
// the held-out fold saw the choice of one or four numbers; BIC counts them).
// Each trial is a screening fit: the new effect's own parameters alone, the
// current set held at its all-window fit, on the windows where the trial
// can act (after the step time; near the box); its cost is what it removes
// there: its final cost minus those windows' costs without it, each window's
// anchor fitted (CrossValidator::settled_costs), so that trials over
// different windows compare. The chosen set is then
// cross-validated with every parameter free.
//  * radius_step.t: profile search of that cost over [start + head, end of
//    the last window - coarse/2], head = the shorter of step_head_s and the
//    first window (earlier, a step is a radius_error): a grid of
//    coarse = step_coarse_s (head/2 by default), but at least 1/32 of
//    the time the windows cover in that span (gaps between pooled
//    recordings skipped; so the number of fits does not grow with the
//    track: the search costs linear time), then +-0.6 coarse in steps
//    of coarse/5, then each level +- the last step in steps of a fifth of
//    it (at least step_fine_s) down to step_fine_s (with the default coarse
//    step: +-coarse/5 in steps of step_fine_s). The points of a level are
//    fitted in parallel, all warm-started from the same fit (the current
//    set's for the coarse grid, then the best point's so far). After the
//    first search, later forward steps start from the previous time and
//    refine +-0.4 coarse, then finely.
//  * slip_zone box (choose_zone_box, zone_boxes.h): zone_candidates on the all-window
//    residuals of the current set, plus SelectOptions::zone_boxes (e.g. from
//    locate.h); each box is screened (s_l, s_r beside S, on the windows
//    that come within 1 m of it), the lowest cost wins, and its edges are refined by coordinate search on the
//    fit cost in steps of half the box's own grid cell (zone_boxes.h: boxes
//    come from grids of 1, 2 and 4 zone_cell_m) halved down to zone_cell_m/4
//    (up to 4 rounds each,
//    first improvement in edge order; the moves are fitted speculatively
//    in parallel, zone_boxes.h),
//    unless its fitted slips are both below 0.01 and its fit cost fell by
//    less than 11.23 (half chi-square(6) at 99.9 %): a box from noise. Edges
//    across which the robot never drives are not determined by the data
//    (typically the two sides of a path that runs through the patch): each
//    edge in turn is moved out to the "isotropic patch" (the square centred
//    on the span of the reference samples inside the box, with the box's
//    larger extent as its side), or if that costs, half or a quarter of the
//    way, and kept where the fit cost rises by less than 1.92 (half the 95 %
//    point of chi-square with 1 degree of freedom), i.e. where the data
//    cannot tell. Without that convention such an edge would sit wherever
//    the refinement stopped, hugging the path; with it, a patch crossed
//    lengthwise is reported as wide as it is long. An edge that the data
//    does determine (samples outside it show no slip) does not move.
//
// Final model: the selected structure fitted (fit.max_iterations, from the
// no-op values) on the training windows of the selection input, and scored
// there before/after on training and held-out windows (FitSummary::train,
// ::heldout): against the denoised reference (less noise, so the held-out
// before/after difference stands out of it; the anchors are free as in the
// search). baseline_pos_rmse_m is the raw one. Training windows: the first
// (1 - heldout_fraction) of the windows, the rest held out ("last"); the
// held-out windows are spread evenly instead ("interleaved") when the
// "last" training part holds less than half of the reference samples where
// radius_step (after t) or slip_zone (inside the box) acts, or the held-out
// part none of them, or its fit is rank deficient. The evenly spread
// pattern is rotated by the fewest windows that meets the same rule (e.g.
// with 4 windows of 60 s and a step at 165 s, holding out the window that
// contains the step keeps the 40 s after it for training).
// `explains` of an effect = (training SSE without it - training SSE with
// all) / baseline training SSE (normalised; the set without it refitted on
// the same training windows).
//
// Deterministic (no randomness); parallel with OpenMP where fits are
// independent (the candidates of a forward step and their folds, one batch
// of CrossValidator::cross_validate_all that the rules read afterwards; the
// backward removals; grid points; boxes), each fit single-
// threaded and started from values fixed before the parallel batch, so the
// results are the same for any number of threads. Logs are data:
// Selection::records (time_s of a candidate: its discrete search plus an
// equal share of its step's parallel batch).
#pragma once

#include <string>
#include <vector>

#include "diagnose/diag_input.h"
#include "diagnose/effect_model.h"
#include "diagnose/fit.h"
#include "diagnose/materiality.h"
#include "diagnose/zone_boxes.h"

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
  int step = 0;           // forward step (1, 2, ...), backward round, 0 for the baseline
  std::string phase;      // "baseline", "forward", "backward", "pair", "swap", "look-alike"
  std::string candidate;  // effect added (forward) or removed (backward); "" for the baseline
  std::string set;        // the evaluated set (structure; discrete parameters shown)
  double cv_score = 0.0;  // pooled held-out normalised MSE per sample (NaN: failed)
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
  std::vector<std::string> rivals;
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
Selection select_effects(const DiagInput& in, const SelectOptions& options = {});

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

// The window length select_effects uses on `in` (header comment, "Windows").
double selection_window_s(const DiagInput& in, const SelectOptions& options);

}  // namespace odotune::diagnose

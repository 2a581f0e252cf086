// Whether a benchmark case's true effects are detectable at all, decided from
// the truth (docs/diagnosis/benchmark.md, "Detectable"):
// the true model's held-out gain must be material against the reference
// noise, by the same floor that a finding must pass (odotune/diagnose/materiality.h).
//
// Setting (the diagnosis's own, at default options): the selection input
// (odotune/diagnose/select.h selection_input: the reference thinned to ~10 Hz and
// denoised, when that keeps the windows), windows of selection_window_s, and
// the default held-out share (SelectOptions::heldout_fraction, 0.3) taken
// from the end: the last windows that hold at least 30 % of the scored
// reference samples. (The diagnosis holds out the last round(0.3 n) of the n
// windows; counting samples instead keeps a short last window, e.g. 1.5 s
// after three full 20 s windows, from being the whole held-out evidence.)
// Position RMSEs are pooled over the held-out windows' samples.
//  * nominal_heldout_m: the nominal model (window_replay.h replay(), anchors
//    as the diagnosis's replay chooses them);
//  * floor_m = materiality_floor_m(in.ref_sigma_m, nominal_heldout_m).
//  * A wheel-odometry effect e (every effect but gyro_bias, gyro_scale):
//    gain_e = RMSE(true wheel effects without e) - RMSE(all true wheel
//    effects), each replayed with the TRUE parameters (diagnose::EffectSet);
//    with one wheel effect "without e" is the nominal model.
//  * A gyro effect e: the same difference for gyro-heading dead reckoning
//    (the wheels' nominal travel, the gyro's yaw rate corrected by the true
//    gyro_bias/gyro_scale, with e's correction left out; lateral_skid's true
//    k when the case has it), which is how odotune/diagnose/diagnosis.cpp proves a
//    gyro finding against a reference heading; its floor uses the raw
//    gyro-heading replay's held-out RMSE as the nominal one. (With fixes only
//    the diagnosis proves gyro effects with its own 40 s windows,
//    gyro_fixes_check.h; the windows here are the selection's.)
//  * detectable_e  <=>  gain_e >= floor (is_material), or, for a wheel effect
//    against a reference heading (ground truth with gt_theta), the held-out
//    heading error it removes passes the heading floor max(min_gain_sigmas *
//    ref_sigma_rad, min_gain_share * nominal held-out heading RMSE): rule
//    (e) of select.h accepts either, since a free-anchored window shows a
//    wheel differential more in heading than in position.
//  * slip_zone and radius_step act only in some places or after some time,
//    and are judged on all windows but the one where the effect gains most
//    (gain and floor, in position or heading, over the others): an effect
//    seen in one window only (a slip zone crossed once, the robot drifting
//    away from it afterwards, as command odometry with 14 % slip does; one
//    crossing in ground truth with gaps) cannot be
//    both fitted and proven on data the fit did not see (every fold that
//    holds that window out fits a no-op), so it is not detectable by the
//    rule a finding must pass, even when the held-out tail holds it. When
//    they are not detectable on the held-out windows but are on the others
//    (e.g. the robot, drifting under the effect, misses the box in its last
//    laps), they are judged on all windows instead
//    (EffectTruth::on_all_windows), because the diagnosis moves its held-out
//    windows to where these two act (diagnosis-design.md "Model selection", "interleaved"), and the truth
//    has no fitted parameter a held-out window would guard against.
// Effects whose parameters equal their no-op values are never detectable.
// Deterministic; no I/O.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/materiality.h>
#include <odotune/studies/diagnosis_cases.h>

namespace odotune::studies {

struct EffectTruth {
  TrueEffect effect;
  bool gyro = false;  // judged by gyro-heading replay
  bool detectable = false;
  bool on_all_windows = false;  // judged on every window (slip_zone, radius_step; header comment)
  double before_m = std::numeric_limits<double>::quiet_NaN();  // held-out RMSE without it
  double after_m = std::numeric_limits<double>::quiet_NaN();   // with every true effect
  double gain_m =
      std::numeric_limits<double>::quiet_NaN();  // removed error: sqrt(before^2 - after^2) (materiality.h)
  double floor_m = std::numeric_limits<double>::quiet_NaN();
  // Wheel effects against a reference heading: the held-out heading error it
  // removes and the materiality rule's heading floor (NaN otherwise; header comment).
  double heading_gain_rad = std::numeric_limits<double>::quiet_NaN();
  double heading_floor_rad = std::numeric_limits<double>::quiet_NaN();
};

struct Detectability {
  std::vector<EffectTruth> effects;  // the case's effects, table order
  double ref_sigma_m = 0.0;          // DiagInput::ref_sigma_m
  double window_s = 0.0;
  int windows = 0, heldout_windows = 0;
  double nominal_heldout_m = std::numeric_limits<double>::quiet_NaN();  // wheel (or command) replay
  double true_heldout_m = std::numeric_limits<double>::quiet_NaN();     // all true wheel effects
  double floor_m = std::numeric_limits<double>::quiet_NaN();            // of the wheel replay
  int detectable_count() const;
};

// Throws std::invalid_argument for an effect the diagnosis's model does not
// know, or a replay that cannot run on `in`.
Detectability assess_detectability(const diagnose::DiagInput& in, const std::vector<TrueEffect>& truth,
                                   const diagnose::MaterialityOptions& materiality = {});

// A multi-recording case (diagnosis_cases.h): several recordings of one
// robot, diagnosed on `fit` pooled and proven on `heldout`, as
// diagnose::diagnose_recordings does (odotune/diagnose/recordings.h).
//  * Wheel-odometry effects are judged on the held-out recordings, where the
//    diagnosis proves them: each held-out recording replayed on its own
//    windows (window_replay.h, raw reference) with the window length the
//    pooled diagnosis uses (selection_window_s of the fit recordings laid end
//    to end as diagnose_recordings lays them), RMSEs pooled over their
//    reference samples; nominal_heldout_m, true_heldout_m and each effect's
//    before_m (the true wheel effects without it) as for one track;
//    floor_m = materiality_floor_m(pooled reference sigma, nominal_heldout_m),
//    the reference sigma pooled as an RMS over the held-out recordings'
//    samples; the heading rule likewise with pooled heading RMSEs.
//  * Gyro effects are judged as assess_detectability judges them, on the fit
//    recordings laid end to end: the diagnosis checks the gyro there.
// No window is left out (slip_zone and radius_step, which need that rule,
// are not drawn for multi-recording cases); windows and heldout_windows count
// the held-out recordings' windows. Throws as assess_detectability, and
// std::invalid_argument for an empty `fit` or `heldout`.
Detectability assess_recordings_detectability(const std::vector<diagnose::DiagInput>& fit,
                                              const std::vector<diagnose::DiagInput>& heldout,
                                              const std::vector<TrueEffect>& truth,
                                              const diagnose::MaterialityOptions& materiality = {});

}  // namespace odotune::studies

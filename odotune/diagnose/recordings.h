// Several recordings of one robot: the diagnosis fitted on
// some recordings and proven on others, reported per recording and pooled.
//
// Pooling. The fit recordings are laid end to end in one DiagInput
// (concatenate): each later recording's times shifted to start gap_s after
// the previous one's end, wheel angles continued, reference weights kept
// (and scaled when the recordings' reference sigmas differ). gap_s exceeds
// any replay window the selection may use, so no window spans two
// recordings, and dead reckoning never crosses a gap. diagnose() then runs on
// the pooled input as on one track (selection, cross-validation over time
// blocks, which now also fall between recordings; the pooled split).
//
// Held-out recordings. With held-out recordings, the pooled result's
// held-out numbers and every wheel finding's `fit.heldout` come from them,
// which the fit never saw: before = the chosen model without the finding (the
// nominal model for the pooled numbers), after = the chosen model, replayed on
// each held-out recording's own windows (window_replay.h, raw reference);
// pooled over their reference samples. A wheel finding holds there when it
// removes at least their materiality floor (materiality.h, from their pooled
// nominal error and sigmas) in position or in heading; one that does not (it
// fits the fitted recordings only, e.g. one recording's own radius
// tolerance) is dropped from the findings and the reported model, listed in
// `not_confirmed`, and the others are tested again against the reduced model
// (not refitted). The pooled model is proven on them when it is material and
// the paired test over their windows (paired_test.h paired_windows, raw
// reference, options.heldout_alpha) is significant; each finding carries
// the same test of itself (`heldout_test`), as evidence. Gyro
// findings keep the pooled split's numbers (the gyro check runs on the fit
// recordings).
//
// Per recording: its nominal and chosen-model position RMSE over its windows,
// whether it was held out, and the chosen wheel structure refitted on that
// recording alone (free anchors, as the selection fits): what holds across
// recordings is the parameters agreeing within their spread, and the pooled
// model helping every recording by at least its own materiality floor.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/diagnosis.h>

namespace odotune::diagnose {

struct RecordingResult {
  std::string track;
  bool heldout = false;     // proven on, not fitted on
  double duration_s = 0.0;  // odometry span [s]
  std::size_t ref_samples = 0;
  double ref_sigma_m = 0.0;
  BeforeAfter error;     // nominal -> chosen (pooled) model, position RMSE over its windows
  double floor_m = 0.0;  // its materiality floor (materiality.h) against its nominal error
  bool helped = false;   // error.before - error.after >= floor_m
  std::vector<NamedValue> refit, refit_stderr;  // "effect.param", fitted on this recording alone
  std::string note;                             // e.g. why the refit could not run
  // Its own sensor checks (sensor_checks.h): reference / odometry ground
  // speed and yaw rate (NaN when not measurable), and how late the motion
  // is against the odometry [s] (NaN when not measured).
  double speed_ratio = std::numeric_limits<double>::quiet_NaN();
  double yaw_ratio = std::numeric_limits<double>::quiet_NaN();
  double motion_late_s = std::numeric_limits<double>::quiet_NaN();
  // Fit recordings: pooled time (the pooled findings' segments) = own time +
  // this [s]; NaN for held-out recordings.
  double pooled_time_offset_s = 0.0;
};

struct PooledDiagnosis {
  DiagInput input;   // the concatenated fit recordings the pooled diagnosis ran on
  Diagnosis pooled;  // on the concatenated fit recordings (see the file comment for held-out numbers)
  bool heldout_recordings = false;
  HeldoutTest heldout_test;  // the pooled model against the nominal one on the held-out recordings
  std::vector<RecordingResult> recordings;  // fit recordings first, in the order given
  // What holds across recordings and what does not, one sentence each.
  std::vector<std::string> consistency;
};

// "paired test over N windows, M informative, K better: rank p = …, t p = …,
// Stouffer p = …", for a summary line.
std::string describe(const HeldoutTest& t);

// Throws std::invalid_argument (one line naming the recording) when the
// recordings are not of one robot: another odometry kind, another nominal
// radius or wheel base (relative difference above 1e-9), reference heading or
// commands on some and not on others.
void check_one_robot(const std::vector<DiagInput>& parts);

// The recordings laid end to end (file comment); throws as check_one_robot.
// shifts (optional): per part, pooled time = its own time + shift [s].
DiagInput concatenate(const std::vector<DiagInput>& parts, double gap_s, std::vector<double>* shifts = nullptr);

// The fit recordings laid end to end as diagnose_recordings pools them
// (concatenate with its gap); throws as concatenate.
DiagInput pool_recordings(const std::vector<DiagInput>& fit, std::vector<double>* shifts = nullptr);

// Diagnoses `fit` pooled and proves on `heldout` (may be empty: then the
// pooled split, as for one track). Throws std::invalid_argument (one line)
// for an empty `fit`, recordings of different robots, or invalid options.
PooledDiagnosis diagnose_recordings(const std::vector<DiagInput>& fit, const std::vector<DiagInput>& heldout,
                                    const DiagnoseOptions& options = {});

}  // namespace odotune::diagnose

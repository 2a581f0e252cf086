// The sim-to-real diagnosis of one track (docs/diagnosis-design.md step 8):
// sensor checks, model selection, location, and the findings of
// ../shared/specs/diagnosis-output.md as a value. No I/O: the CLI
// (odotune/cli/cmd_diagnose.cpp) prints, writes the JSON, the figures and the
// scenario. Why the findings and their numbers are defined as below:
// docs/diagnosis-design.md, "A diagnosis's findings and their numbers".
//
// Findings, in order of importance (`explains`, largest first):
//  * wheel-odometry effects chosen by select_effects (select.h), fitted on
//    its training windows; params/stderr from the fit (Ceres covariance; the
//    discrete parameters radius_step.t and the slip_zone box carry the
//    profile search's resolution as their stderr and are listed in
//    `discrete`);
//  * gyro effects (gyro_bias, gyro_scale) whose sensor check departs from the
//    no-op value (sensor_checks.h Verdict::departs), judged against the
//    reference heading, or with position fixes only by gyro_fixes_check.h;
//  * `unexplained`: segments where the chosen model's residuals still grow
//    faster than noise (locate.h), carrying at least unexplained_min_share of
//    its squared error, at least unexplained_min_sigmas reference sigmas, and
//    reproduced on held-out windows by the term search (term_search.h),
//    whose terms it carries as `model`; growth no term reproduces is listed
//    in `not_reproduced` instead.
// Every finding is material (materiality.h, options select.materiality); one
// that is not is listed in `immaterial`.
//
// Numbers of a finding (position RMSEs of the windowed replay, [m]):
// baseline/final against the raw reference; train/heldout before/after
// against the selection's denoised reference (cross_validate.h's
// denoised_reference; a reference slower than about 10 Hz, e.g. fixes, as
// it is).
//  * wheel effect e: before = the chosen model without e, after = the chosen
//    model; explains = select.h's share of the baseline training SSE.
//  * gyro effect: gyro_heading_replay with the chosen wheel model's travel,
//    before = raw gyro, after = corrected; explains = the share of its
//    training SSE the correction removes.
//  * where: the segments where `before`'s residuals grow faster than noise
//    (locate.h), else the windows where the effect reduces the error most
//    (at least half the largest reduction); conditions = locate's phrase,
//    else the effect's physical description.
//
// Deterministic: same input and options, same numbers.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/finding_kind.h>
#include <odotune/diagnose/gyro_fixes_check.h>
#include <odotune/diagnose/locate.h>
#include <odotune/diagnose/paired_test.h>
#include <odotune/diagnose/select.h>
#include <odotune/diagnose/sensor_checks.h>
#include <odotune/diagnose/term_search.h>

namespace odotune::diagnose {

struct DiagnoseOptions {
  SelectOptions select;  // select.fit.window_s is the replay window of the output
  SensorCheckOptions sensors;
  GyroFixesOptions gyro_fixes;  // gyro effects with position fixes only
  LocateOptions locate;
  double unexplained_min_share = 0.2;   // of the final model's SSE inside the located segments
  double unexplained_min_sigmas = 3.0;  // its RMSE there, in reference sigmas (DiagInput::ref_sigma_m)
  TermSearchOptions terms;              // physics outside the list (term_search.h)
  // One-sided level of the paired test over held-out recordings' windows
  // (recordings.h) that proves the pooled model on them.
  double heldout_alpha = 0.05;

  bool IsValid(std::string* why) const;
};

struct NamedValue {
  std::string name;
  double value = std::numeric_limits<double>::quiet_NaN();
};

struct BeforeAfter {
  double before_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();
  double after_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();
};

// Held-out recordings' verdict on a model against another (recordings.h):
// pooled position RMSE over their windows, their materiality floor, and the
// paired tests over their windows.
struct HeldoutTest {
  BeforeAfter error;
  double floor_m = std::numeric_limits<double>::quiet_NaN();
  int windows = 0;
  PairedComparison paired;  // over their windows (paired_test.h), at DiagnoseOptions::heldout_alpha
  bool material = false;    // removes at least their floor, in position or in heading
  bool proven = false;      // material and paired.significant
};

struct Finding {
  FindingKind kind;                   // an effect of physics-effects.md, or Unexplained
  std::vector<NamedValue> params;     // the spec's parameter names, table order
  std::vector<NamedValue> stderrs;    // same names
  std::vector<std::string> discrete;  // parameters found by a profile search
  std::vector<TimeSegment> segments;  // where.segments
  std::vector<MapRegion> regions;     // where it is a matter of place
  std::string conditions;             // where.conditions
  double explains = 0.0;
  BeforeAfter train, heldout;
  std::vector<Effect> rivals;               // confounded alternatives the data could not rule out
  std::string evidence;                     // how it was found, one phrase
  std::optional<TermModel> model;           // unexplained only: terms that reproduce it (term_search.h)
  std::optional<HeldoutTest> heldout_test;  // wheel effects, with held-out recordings (recordings.h)

  double param(std::string_view name) const;  // NaN when absent
  bool is(Effect e) const { return kind == FindingKind{e}; }
  bool is_unexplained() const { return std::holds_alternative<Unexplained>(kind); }
  // A wheel-odometry effect: neither a gyro effect nor `unexplained`.
  bool is_wheel_effect() const;
  // The effect of a finding that is not `unexplained` (throws std::bad_variant_access for it).
  Effect effect() const { return std::get<Effect>(kind); }
  std::string_view name() const { return to_string(kind); }  // the spec's "effect"
  // The simulator's command-line form, "lateral_skid:k=0.021" ("" for unexplained).
  std::string spec() const;
};

// A gyro effect that was significant but fell below its materiality floor.
struct ImmaterialEffect {
  Effect effect = Effect::gyro_bias;
  std::string line;  // "spec: why", as the JSON and the summary list it
};

// Wall-clock seconds of diagnose()'s steps, each what its name says.
struct DiagnosisTiming {
  double total_s = 0.0;    // the whole diagnose() call
  double sensors_s = 0.0;  // check_sensors
  double select_s = 0.0;   // selection_input and select_effects
  double locate_s =
      0.0;               // the location only: every locate() call (the residuals, each wheel finding's `where`)
  double terms_s = 0.0;  // the term search (term_search.h)
};

struct Diagnosis {
  std::string track;
  ReferenceKind reference = ReferenceKind::gt;
  std::size_t ref_gt_samples = 0, ref_fix_samples = 0;  // reference samples of each source (diag_input.h)
  bool ref_heading = false;                             // compared against a reference heading too
  std::string velocity_source;  // body-velocity odometry: "command" or "velocity odometry" (diag_input.h)
  // The sensor checks reconciled with the findings (reconcile.h): per flagged
  // check, which finding carries it or why none does.
  std::vector<std::string> sensor_notes;
  double window_s = 0.0;
  double baseline_pos_rmse_m = 0.0, baseline_heading_rmse_rad = 0.0;  // nominal, all windows
  double final_pos_rmse_m = 0.0, final_heading_rmse_rad = 0.0;        // chosen model, all windows
  BeforeAfter train, heldout;                 // nominal vs chosen model on the selection's split
  bool scored_on_denoised_reference = false;  // train/heldout numbers (file comment)
  std::vector<Finding> findings;              // by importance; empty = nothing beyond noise
  EffectSet model;                            // chosen wheel effects and gyro effects, fitted values
  std::vector<int> train_windows, heldout_windows;
  Selection selection;
  SensorCheck sensors;
  bool has_gyro_fixes = false;  // gyro_fixes is set (fixes-only reference with a gyro)
  GyroFixesCheck gyro_fixes;
  ResidualSeries before, after;  // nominal and chosen model, all windows
  Location located_before, located_after;
  TermSearchResult term_search;  // the search on the chosen model's mismatch (term_search.h)
  DiagnosisTiming timing;
  std::string note;  // e.g. why selection could not run
  // Materiality (materiality.h): the floor [m] against the nominal held-out
  // error of the final split, and the gyro effects that were significant but
  // fell below their floor, one line each ("spec: why").
  double floor_m = 0.0;
  std::vector<ImmaterialEffect> immaterial;
  // Located growth that would have been `unexplained` but that no term of the
  // term search reproduces on held-out windows (file comment), one line each.
  std::vector<std::string> not_reproduced;
  // Wheel findings of the fitted recordings that remove less than the
  // held-out recordings' floor there (recordings.h), one line each; empty for
  // one track.
  std::vector<std::string> not_confirmed;
};

// Throws std::invalid_argument (one line) for invalid options or an input the
// steps cannot use.
Diagnosis diagnose(const DiagInput& in, const DiagnoseOptions& options = {});

}  // namespace odotune::diagnose

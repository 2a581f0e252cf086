// `odotune diagnose` as one call: read a recording, optionally cut it to a
// time interval, find what the nominal robot model leaves out
// (odotune/diagnose/diagnosis.h) and write the outputs asked for. Computation and
// file output only; the command prints the summary.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <odotune/diagnose/diagnosis.h>
#include <odotune/diagnose/recordings.h>
#include <odotune/jobs/controller_export.h>

namespace odotune::jobs {

struct DiagnoseRequest {
  // Track files (../shared/specs/track-format.md): one recording, or several
  // recordings of one robot fitted pooled (odotune/diagnose/recordings.h).
  std::vector<std::string> tracks;
  std::vector<std::string> heldout;  // recordings of the same robot to prove on, never fitted
  std::string json;                  // diagnosis JSON (diagnosis-output.md); empty = not written
  std::string report;                // folder for the figures and index.html; empty = none
  std::string scenario_out;          // the robot with the fitted effects (and the terms of an unexplained
      // finding's model, odotune/sim/model_terms.h) as a scenario YAML; empty = none
  double window_s = 20.0;  // replay window [s]; the odometry is re-anchored at each
  // Materiality floor of a finding's held-out gain (odotune/diagnose/materiality.h):
  // max(min_gain_sigmas reference sigmas, min_gain_share of the nominal error).
  diagnose::MaterialityOptions materiality;
  // Track-time interval to diagnose [s]. The track is cut (diagnose::crop)
  // only when one of them is given; neither: the whole track.
  std::optional<double> from_s, to_s;
  // --controller-out and its flags (odotune/jobs/controller_export.h; no nominal
  // overrides): the nominal robot × the fitted radius_error and
  // wheel_base_error scales as the controller's parameters.
  ControllerRequest controller;
};

struct DiagnoseOutcome {
  diagnose::Diagnosis diagnosis;  // several recordings: the pooled one (= pooled.pooled)
  bool several = false;           // several recordings (or held-out ones) were given
  diagnose::PooledDiagnosis pooled;
  // diagnosis_summary(): the one-sentence first line, then the details.
  std::vector<std::string> summary;
  // --controller-out: the line saying what was written, or that no
  // radius_error or wheel_base_error was found and no file was written
  // (an existing file is left as it is); "" without --controller-out.
  std::string controller_line;
};

// Reads the track(s), diagnoses them (several: fitted pooled, proven on the
// held-out ones; the JSON is one document with a `tracks` list, the report
// and the scenario are those of the pooled fit recordings, the scenario
// driven along the first) and writes, in this order: the report folder
// (odotune/results/diagnosis_report.h), the scenario (odotune simulate reads it), the
// controller's parameters (only when radius_error or wheel_base_error was
// found; the flags and the track's nominal geometry are checked before the
// diagnosis), the JSON; each file appears whole or not at all.
// Throws core::Failure (one line naming the track or the report folder)
// when the track cannot be read, cut or diagnosed, the report cannot be
// written or the corrected scenario cannot be built; std::runtime_error
// ("cannot write scenario|diagnosis JSON 'PATH': ...") when a file cannot be
// written.
DiagnoseOutcome run_diagnose(const DiagnoseRequest& request);

}  // namespace odotune::jobs

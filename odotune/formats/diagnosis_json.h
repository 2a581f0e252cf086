// The --json document of `odotune diagnose`: ../shared/specs/diagnosis-output.md
// (format "odotune-diagnosis/1"), every required key, plus:
//   top level: "heldout"/"train" (nominal vs the chosen model on the split),
//     "split", "model" (the fitted effects in the simulator's form, what
//     --scenario-out writes), "sensor_checks", "selection" (the search log),
//     "located" (segments and conditions of the nominal residuals), "timing_s",
//     "note";
//   per finding: "rivals", "evidence", "discrete" (parameters found by a
//     profile search: their stderr is the search resolution),
//     "where.regions" ([[x0, x1, y0, y1], ...] in metres).
// Numbers are SI; an undetermined number (NaN) is written as null.
#pragma once

#include <nlohmann/json.hpp>

#include <odotune/diagnose/diagnosis.h>
#include <odotune/diagnose/recordings.h>

namespace odotune::formats {

nlohmann::json diagnosis_json(const diagnose::Diagnosis& d);

// Several recordings (odotune/diagnose/recordings.h): ONE document whose spec keys
// are the pooled result's (diagnosis_json of p.pooled; with held-out
// recordings, fit.heldout and "heldout" come from them), plus "tracks": one
// entry per recording {"track", "role": "fit" | "heldout", "duration_s",
// "reference_samples", "ref_sigma_m", "error": {"before_pos_rmse_m",
// "after_pos_rmse_m"} (nominal -> pooled model over its windows), "floor_m",
// "helped", "refit": {"effect.param": value}, "refit_stderr", "note"}, and
// "consistency" (what holds across recordings, sentences).
nlohmann::json pooled_diagnosis_json(const diagnose::PooledDiagnosis& p);

}  // namespace odotune::formats

// What `tune --model pf-calib|adaptive-pf-calib|ukf` prints on stdout (the
// EKF models print with print_tune_result, cli/output.h).
#pragma once

#include "jobs/calibration_tune_job.h"
#include "jobs/ukf_tune_job.h"

namespace odotune::cli {

// Settings (names, units), score before/after, pose errors before/after per
// track.
void print_calibration_outcome(const CalibrationTuneOutcome& o);
// Errors before/after (mean and per track), the tuned values, the solver's
// evaluations.
void print_ukf_outcome(const UkfTuneOutcome& o);

}  // namespace odotune::cli

// What `tune` prints on stdout: a heading naming the model, tracks, fitness
// mode and solver, then the result (the EKF models and the UKF with
// print_tune_result, odotune/cli/output.h).
#pragma once

#include <odotune/jobs/calibration_tune_job.h>
#include <odotune/jobs/tune_job.h>
#include <odotune/jobs/ukf_tune_job.h>

namespace odotune::cli {

// EKF models: errors before/after (mean and per track), the tuned values, the
// solver's evaluations and diverged evaluations.
void print_tune_outcome(const jobs::TuneOutcome& o);
// Calibrators: settings (names, units), score before/after, pose errors
// before/after per track.
void print_tune_outcome(const jobs::CalibrationTuneOutcome& o);
// UKF: errors before/after (mean and per track), the tuned values, the
// solver's evaluations.
void print_tune_outcome(const jobs::UkfTuneOutcome& o);

}  // namespace odotune::cli

// `odotune tune` without its flags (odotune/cli/cmd_tune.cpp reads those and prints):
// which model, which options apply to it, the tracks loaded and prepared for
// it, the EKF, calibrator or UKF tune (tune_job.h, calibration_tune_job.h,
// ukf_tune_job.h) and its --json and --config-out files:
//
//   EKF (rq, alpha, gyro)    --json tune_json.h,             --config-out odotune-ekf-config/1
//   pf-calib, adaptive-…     --json calibration_tune_json.h, --config-out odotune-pf-config/1
//   ukf                      --json ukf_tune_json.h,         --config-out odotune-ukf-config/1
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <odotune/jobs/calibration_tune_job.h>
#include <odotune/jobs/tune_job.h>
#include <odotune/jobs/ukf_tune_job.h>
#include <odotune/objectives/tuned_model.h>

namespace odotune::jobs {

// The result of one of the three tunes.
using TuneCommandOutcome = std::variant<TuneOutcome, CalibrationTuneOutcome, UkfTuneOutcome>;

// The solver settings (with `progress` and `stop`, which the tune passes on)
// and the rest of the command's options, each choice parsed by the caller
// (odotune/cli/cmd_tune.cpp parses the flags once).
struct TuneCommandRequest : SolverSettings {
  std::vector<std::string> tracks;  // track files; the fitness is the mean over them
  // rl-ekf and rl-ukf are refused (they are tuned from their parameter file
  // and bag: rl_job.h).
  objectives::TunedModel model = objectives::TunedModel::ekf(filters::NoiseModel::rq);
  // EKF: any fitness mode; UKF: 1..7. Not given: the default (7), or 8 for
  // an EKF tune on a track without ground truth.
  std::optional<objectives::FitnessMode> mode;
  objectives::FixCvOptions fix_cv;  // EKF modes 8, 9: the folds (odotune/objectives/fix_cv_replay.h)
  // Calibrators only: the calibrator's fixed parts (calibration_tune_job.h);
  // given for another model, a Failure names the flag (as --mode for a
  // calibrator).
  std::optional<filters::Resampler> resampler;    // not given: systematic
  std::optional<filters::ResamplePolicy> policy;  // not given: neff
  std::optional<int> pf_particles;                // not given: the paper's 5000 / 8000
  std::optional<std::uint64_t> pf_seed;           // not given: 1
  std::optional<double> ext_from_gt_hz;           // [Hz]; not given: the tracks' own v_ext/w_ext
  std::string json_out, config_out;               // files to write; empty: none
  // Called with the result when the tune has ended (finished or stopped),
  // before the files are written: where the command prints it.
  std::function<void(const TuneCommandOutcome&)> report;
};

// Checks the model and the options, loads and prepares the tracks, runs the
// tune, calls `report`, then writes --json and --config-out (in that order).
// A raised `stop` ends the tune early with the best found so far, which is
// reported and written as a finished tune's (the caller tells the user).
// Throws core::Failure (one line) for an rl-ekf or rl-ukf model, an option
// of another model, invalid settings, an unusable track or a solver failure
// (nothing is reported or written then), and for a file that cannot be
// written (after `report`; --json's failure leaves --config-out unwritten).
TuneCommandOutcome run_tune_command(const TuneCommandRequest& request);

}  // namespace odotune::jobs

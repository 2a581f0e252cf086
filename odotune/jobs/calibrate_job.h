// `odotune calibrate`: an online (or batch) calibration of the odometry
// parameters R_R, R_L and D from wheel rates and external body velocities
// (Fariña, Toledo & Acosta, RA-L 2026; odotune/calibration/calibration_run.h) over
// track files, with its output files; and the replay of a calibration file
// on held-out tracks (`--apply`). Checking, loading, computing and file
// output only: the command parses the flags and prints the summary lines.
//
// Initial guesses (a choice of this command, not the paper's): the PF draws
// each radius uniformly from its track's nominal ±5 % and the wheel base
// from nominal ±15 %, so any robot size works; for the paper's wheelchair
// (R = 0.32 m, D = 0.65 m) these are 0.304–0.336 m and 0.5525–0.7475 m,
// the paper's 0.305–0.335 m and 0.55–0.75 m to within 2.5 mm. The DKF
// starts at the range's centre with sd = width/√12 (the uniform's sd). The
// calibrators' length-valued tuning constants (PF random walk σ, adaptive α
// and its σ floor, particles per dispersion, DKF random walks) are the paper's wheelchair
// values scaled by R_nom/0.32 m (and D_nom/0.65 m for the DKF's wheel-base
// walk), so a robot with 5 cm wheels gets the same relative noise.
//
// Errors are core::Failure with one line naming the flag or file at
// fault (the command's error messages); nothing is written when a check
// fails.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_run.h>
#include <odotune/calibration/twist_calibration.h>
#include <odotune/filters/odometry_params.h>
#include <odotune/formats/calibration_json.h>
#include <odotune/jobs/controller_export.h>

namespace odotune::jobs {

// The command's flags as plain values (names as the flags'), each choice
// parsed by the caller (odotune/cli/cmd_calibrate.cpp parses the flags once).
struct CalibrateRequest {
  std::vector<std::string> tracks;  // track files, calibrated in this order (one robot)
  // The calibration's flags: a flag not given is nullopt and takes the default
  // named beside it. --resampler, --policy, --particles, --pf-evolution and
  // --pf-memory apply to the PF methods only, --segment to batch-pose,
  // --start, --fix-sigma-m and --pose-memory-m to online-pose, and none
  // of the calibration flags combines with --apply.
  std::optional<calibration::CalibrationMethod> method;  // default adaptive-pf
  // The method's name as given ("batch" is batch-pose's alias), which the
  // outputs' provenance repeats; empty: to_string(method).
  std::string method_spelling;
  // --input: the odometry to calibrate (odotune/tracks/odometry_input.h); nullopt:
  // each track's own. Twist and command tracks take --method batch only
  // (odotune/jobs/twist_calibrate_job.h).
  std::optional<tracks::OdometryInput> input;
  std::optional<filters::Resampler> resampler;    // PF; default systematic
  std::optional<filters::ResamplePolicy> policy;  // PF; default neff
  std::optional<std::uint64_t> seed;              // PF random seed; default 1
  std::optional<int> particles;          // PF particles (adaptive-pf: initial); default 5000 (adaptive 8000)
  int threads = 0;                       // PF threads (0: OpenMP's default); results do not depend on it
  std::optional<double> ext_from_gt_hz;  // derive the external velocities from the ground truth [Hz]
  std::optional<double> ext_sigma_v;     // [m/s] σ of v_ext where the track gives none; default 0.02
  std::optional<double> ext_sigma_w;     // [rad/s] σ of w_ext where the track gives none; default 0.02
  std::optional<std::string> init_radius_range;      // "LO,HI" [m], both radii; default nominal ±5 %
  std::optional<std::string> init_wheel_base_range;  // "LO,HI" [m]; default nominal ±15 %
  std::optional<double> tolerance_pct;               // convergence tolerance [%], in (0, 100); default 0.5
  std::optional<filters::PfEvolution> pf_evolution;  // PF; default evidence
  std::optional<double> pf_memory_s;  // PF evidence evolution: memory after a change [s]; default 10
  std::optional<double> segment_s;    // batch-pose: segment length [s]; default 0, whole runs
  bool fit_start_heading = false;     // batch-pose: fit each segment's start heading too
  std::optional<calibration::OnlinePoseStart> start;  // online-pose; default fixes
  std::optional<double> fix_sigma_m;    // online-pose: the fixes' sd where a track gives no aps_var [m]
  std::optional<double> pose_memory_m;  // online-pose: memory after a change [m rolled]; default 10
  // Output files ("": not written). calibrate: all four; --apply: json only.
  std::string json, csv, figure, config_out;
  std::string apply;  // the calibration file --apply replays
  // --apply: the dead-reckoned paths (nominal and calibrated) and the ground
  // truth of every track as CSV ("": not written): track, t_s, gt_x_m,
  // gt_y_m, nominal_x_m, nominal_y_m, calibrated_x_m, calibrated_y_m.
  std::string paths_csv;
  // --controller-out and its flags (odotune/jobs/controller_export.h); not with --apply.
  ControllerRequest controller;

  // The method, given or the default, and its name as given.
  calibration::CalibrationMethod method_or_default() const {
    return method.value_or(calibration::CalibrationMethod::adaptive_pf);
  }
  std::string method_name() const {
    return method_spelling.empty() ? std::string(calibration::to_string(method_or_default())) : method_spelling;
  }
};

// The calibration itself reports no progress. on_start (when set) gets
// "calibrating with METHOD over N samples…" just before it starts; on_end
// (when set) is called once it has ended, returned or thrown.
struct CalibrateHooks {
  std::function<void(const std::string& status)> on_start;
  std::function<void()> on_end;
};

struct CalibrateOutcome {
  formats::CalibrationRunInfo info;                   // the options that ran, the track files
  std::vector<calibration::CalibrationInput> inputs;  // one per track file, in order
  calibration::CalibrationResult result;
  std::vector<calibration::TrackCalibrationScore> nominal;  // the inputs' nominal parameters, scored
  std::vector<std::string> summary;                         // calibration_summary_lines()
  std::string controller_line;  // --controller-out: what was written ("" without it)
  // Twist and command tracks (odotune/jobs/twist_calibrate_job.h): the fit, and each
  // track's dead reckoning at the identity and at the fit (the fields above
  // stay empty).
  std::optional<calibration::TwistCalibrationSummary> twist;
  std::vector<std::array<calibration::TwistScore, 2>> twist_scores;
};

// Checks the output folders, loads the tracks (one robot: equal nominal
// radii and wheel base), builds the options, runs the calibration and
// writes, in this order, the figure (STEM.png, STEM.svg; gnuplot is the
// likeliest to fail), the CSV trace, the calibration YAML (--config-out, for
// --apply), the controller's parameters (--controller-out, the final
// estimate as --config-out; odotune/jobs/controller_export.h, whose flags are checked
// with the output folders before the run) and the JSON
// (odotune/formats/calibration_json.h). Every file is written atomically, after the
// run. Throws core::Failure.
CalibrateOutcome run_calibrate(const CalibrateRequest& request, const CalibrateHooks& hooks = {});

struct ApplyOutcome {
  filters::OdometryParams params;             // the calibration file's
  std::vector<formats::AppliedTrack> tracks;  // per track: nominal and calibrated scores
  std::vector<std::string> summary;           // apply_summary_lines()
  // A twist or commands file: its correction, and per track the scores at
  // the identity and at the correction (tracks above stays empty).
  std::optional<filters::TwistCorrection> twist;
  std::vector<std::array<calibration::TwistScore, 2>> twist_scores;
};

// --apply: replays request.tracks (which need ground truth; external
// velocities are derived from it at 10 Hz for tracks without them) with the
// calibration file request.apply and with their nominal parameters, and
// writes request.json. Throws core::Failure when a calibration flag or
// another output (--controller-out and its flags too) was given, or on bad
// files.
ApplyOutcome run_calibrate_apply(const CalibrateRequest& request);

}  // namespace odotune::jobs

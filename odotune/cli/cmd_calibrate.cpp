// odotune calibrate: online (or batch) calibration of the odometry
// parameters R_R, R_L and D from wheel rates and external body velocities,
// and the replay of a calibration on held-out tracks (--apply); the work is
// odotune/jobs/calibrate_job.h, the summary text odotune/jobs/calibration_summary.h.
#include <memory>
#include <optional>
#include <string>

#include <fmt/format.h>

#include <odotune/cli/choices.h>
#include <odotune/cli/commands.h>
#include <odotune/cli/controller_options.h>
#include <odotune/cli/output.h>
#include <odotune/cli/progress.h>
#include <odotune/jobs/calibrate_job.h>

namespace odotune::cli {

namespace {

void print_calibrate(const jobs::CalibrateRequest& a) {
  apply_threads(a.threads);
  std::optional<StatusLine> status;
  const jobs::CalibrateOutcome o = jobs::run_calibrate(
      a, {[&](const std::string& text) { status.emplace(text); }, [&] { status.reset(); }});
  print_lines(o.summary);
  if (!a.figure.empty()) fmt::print("figure: {}.png, {}.svg\n", a.figure, a.figure);
  if (!a.csv.empty()) fmt::print("csv: {}\n", a.csv);
  if (!a.config_out.empty())
    fmt::print("calibration: {} (check it on held-out runs: odotune calibrate --apply {} --track …)\n",
               a.config_out, a.config_out);
  if (!o.controller_line.empty()) fmt::print("{}\n", o.controller_line);
  if (!a.json.empty()) fmt::print("json: {}\n", a.json);
}

void print_apply(const jobs::CalibrateRequest& a) {
  const jobs::ApplyOutcome o = jobs::run_calibrate_apply(a);
  print_lines(o.summary);
  if (!a.json.empty()) fmt::print("json: {}\n", a.json);
}

// The method and the particle filter's settings.
void add_method_options(CLI::App* sub, jobs::CalibrateRequest& req) {
  const std::vector<calibration::CalibrationMethod> methods(calibration::kAllCalibrationMethods.begin(),
                                                            calibration::kAllCalibrationMethods.end());
  sub->add_option_function<std::string>(
         "--method",
         [&req, methods](const std::string& text) {
           req.method = parse_choice("--method", text, methods, calibration::parse_calibration_method);
           req.method_spelling = text;  // "batch" stays "batch" in the outputs
         },
         "the calibration method; batch is batch-pose's alias (default adaptive-pf; twist and command tracks: batch)")
      ->type_name(choice_type_name(methods));
  add_enum_option(sub, "--input", req.input, tracks::kAllOdometryInputs,
                  "the odometry to calibrate: wheels (radii and base), twist (a measured v, w: scales) or "
                  "commands (scales and a delay); default: each track's own (docs/track-format.md)");
  add_enum_option(sub, "--resampler", req.resampler, filters::kAllResamplers,
                  "PF resampling scheme (default systematic)");
  add_enum_option(sub, "--policy", req.policy, filters::kAllResamplePolicies,
                  "PF resampling policy (default neff)");
  sub->add_option("--seed", req.seed, "PF random seed (same seed ⇒ same estimates)");
  sub->add_option("--particles", req.particles,
                  "PF particles (adaptive-pf: the initial count; default 5000, adaptive 8000)")
      ->check(CLI::PositiveNumber);
  add_enum_option(sub, "--pf-evolution", req.pf_evolution, filters::kAllPfEvolutions,
                  "PF parameter evolution: evidence (default: a walk scaled to the "
                  "posterior spread, whose memory grows until a fast-forgetting twin "
                  "predicts better, a change) or paper (§III's fixed or eq. 11 walk)");
  sub->add_option("--pf-memory", req.pf_memory_s,
                  "PF evidence evolution: the memory after a detected change [s] "
                  "(default 10)")
      ->check(CLI::PositiveNumber);
}

// The external velocities: from the track, or derived from its ground truth.
void add_ext_options(CLI::App* sub, jobs::CalibrateRequest& req) {
  sub->add_option("--ext-from-gt", req.ext_from_gt_hz,
                  "derive the external velocities from the ground truth at this rate [Hz] (for tracks "
                  "without v_ext/w_ext, e.g. OptiOdom)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--ext-sigma-v", req.ext_sigma_v,
                  "σ of the external speed [m/s] where the track gives no v_ext_var (and for --ext-from-gt, "
                  "instead of the σ estimated from the ground truth's jitter); default 0.02")
      ->check(CLI::PositiveNumber);
  sub->add_option("--ext-sigma-w", req.ext_sigma_w,
                  "σ of the external yaw rate [rad/s] where the track gives no w_ext_var (and for "
                  "--ext-from-gt, instead of the estimated σ); default 0.02")
      ->check(CLI::PositiveNumber);
}

// The initial ranges, the convergence tolerance and the batch fit's segments.
void add_fit_options(CLI::App* sub, jobs::CalibrateRequest& req) {
  sub->add_option("--init-radius-range", req.init_radius_range,
                  "LO,HI: initial range of both radii [m] (default nominal ±5 %)");
  sub->add_option("--init-wheel-base-range", req.init_wheel_base_range,
                  "LO,HI: initial range of the wheel base [m] (default nominal ±15 %)");
  sub->add_option("--tolerance", req.tolerance_pct,
                  "convergence: within this % of the truth from then on (default 0.5)");
  sub->add_option("--segment", req.segment_s,
                  "batch-pose: dead-reckon segments of this length [s] from a reference "
                  "pose (default 0: whole runs; twist and command tracks 10)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--fit-start-heading", req.fit_start_heading,
                "batch-pose: fit each segment's start heading too (ground truth; with fixes the whole start "
                "pose is always fitted)");
  add_enum_option(sub, "--start", req.start, calibration::kAllOnlinePoseStarts,
                  "online-pose: each run's start pose: fixes (default: acquired from the first fixes) or known "
                  "(the run's first ground-truth pose)");
  sub->add_option("--fix-sigma-m", req.fix_sigma_m,
                  "online-pose: the fixes' sd [m] where a track gives no aps_var_x/aps_var_y")
      ->check(CLI::PositiveNumber);
  sub->add_option(
         "--pose-memory-m", req.pose_memory_m,
         "online-pose: the geometry's memory after a detected change, in metres rolled (default: 10, or 100 × "
         "the fixes' median sd when longer)")
      ->check(CLI::PositiveNumber);
}

// The outputs, and --apply.
void add_output_options(CLI::App* sub, jobs::CalibrateRequest& req) {
  sub->add_option("--json", req.json, "write the result as JSON to this file");
  sub->add_option("--csv", req.csv, "write the estimates over time as CSV to this file");
  sub->add_option("--figure", req.figure, "write the estimates over time as STEM.png and STEM.svg");
  sub->add_option("--config-out", req.config_out,
                  "write the calibrated parameters (YAML, odotune-calibration/1) for --apply");
  sub->add_option("--paths-csv", req.paths_csv,
                  "--apply: write the dead-reckoned paths (nominal, calibrated) and the ground truth as CSV");
  sub->add_option("--apply", req.apply,
                  "replay the tracks with this calibration file and with their nominal parameters, and "
                  "compare pose and heading RMSE (no calibration is run)");
}

}  // namespace

void register_calibrate(CLI::App& app) {
  auto req = std::make_shared<jobs::CalibrateRequest>();
  auto* sub = app.add_subcommand(
      "calibrate",
      "Calibrate the odometry (wheel radii, wheel base) from external velocities or position fixes");
  sub->footer(
      "Examples:\n"
      "  odotune calibrate --track run_cw.csv --track run_ccw.csv --method adaptive-pf --seed 1 \\\n"
      "      --json cal.json --csv cal.csv --figure cal --config-out cal.yaml\n"
      "  odotune calibrate --apply cal.yaml --track held_out.csv --json held_out.json\n"
      "  odotune calibrate --track optiodom.csv --ext-from-gt 10 --method dkf\n"
      "  odotune calibrate --track mrclam-robot1.csv --method batch --config-out cmd.yaml   (commands: scales, delay)\n"
      "  odotune fixes optiodom.csv -o fixed.csv && odotune calibrate --track fixed.csv --method online-pose \\\n"
      "      --fix-sigma-m 0.06\n"
      "Methods (Fariña, Toledo & Acosta, RA-L 2026): adaptive-pf and pf (particle filters), dkf (dual\n"
      "Kalman filter), batch (offline least squares), none (the nominal parameters); online-pose (an EKF\n"
      "over pose and geometry corrected by position fixes, for robots with GPS, motion capture or a\n"
      "localiser instead of a velocity sensor). Several tracks are\n"
      "calibrated one after another with the same filter (as UMBmark combines a clockwise and a\n"
      "counter-clockwise run). The truth, the convergence time and the % errors are known for simulated\n"
      "tracks (their sim.effects metadata); pose and heading RMSE need ground truth. Initial ranges\n"
      "default to the nominal radii ±5 % and wheel base ±15 % (the paper's wheelchair ranges);\n"
      "the DKF starts at the range centre with sd = width/√12.");
  sub->add_option("--track", req->tracks, "track file (repeat for several, calibrated in order)")->required();
  add_method_options(sub, *req);
  add_threads_option(sub, &req->threads);
  add_ext_options(sub, *req);
  add_fit_options(sub, *req);
  add_output_options(sub, *req);
  add_controller_options(sub, req->controller, true);
  sub->callback([=] {
    if (req->apply.empty())
      print_calibrate(*req);
    else
      print_apply(*req);
  });
}

}  // namespace odotune::cli

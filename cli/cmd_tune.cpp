// odotune tune: tune one EKF noise model, one particle-filter calibrator's
// settings (issue 5, item 7), or the velocity-fusion UKF's noise (issue 6,
// item 1), on one or more tracks.
#include <cstdio>
#include <fstream>
#include <iostream>

#include <fmt/format.h>

#include "jobs/calibration_tune_job.h"
#include "jobs/calibration_tune_json.h"
#include "cli/commands.h"
#include "formats/config_yaml.h"
#include "core/failure.h"
#include "cli/output.h"
#include "tracks/track_io.h"
#include "cli/tune_output.h"
#include "jobs/tune_json.h"
#include "formats/pf_config_yaml.h"
#include "cli/progress.h"
#include "jobs/tune_job.h"
#include "objectives/tuned_model.h"
#include "formats/ukf_config_yaml.h"
#include "jobs/ukf_tune_job.h"
#include "jobs/ukf_tune_json.h"
#include "tuner/nlopt_solver.h"

namespace odotune::cli {

namespace {

struct TuneArgs {
  std::vector<std::string> tracks;
  std::string model = "rq";
  int mode = 7;
  std::string solver = "pso";
  std::uint64_t seed = 1;
  int particles = 50, iterations = 150;
  long evals = 0;
  std::string json_out, config_out;
  int threads = 0;
  // Calibrator models only (the fixed parts of the calibrator).
  std::string resampler = "systematic", policy = "neff";
  int pf_particles = 0;
  std::uint64_t pf_seed = 1;
  double ext_from_gt_hz = 0.0;
};

// Options that belong to one kind of model only.
const std::vector<std::string> kEkfOnly = {"--mode"};
const std::vector<std::string> kCalibratorOnly = {"--resampler", "--policy", "--pf-particles",
                                                  "--pf-seed", "--ext-from-gt"};

void print_outcome(const TuneOutcome& o) {
  std::string names;
  for (const auto& t : o.tracks) names += (names.empty() ? "" : ", ") + t.track;
  fmt::print("tuned {} noise on {} for mode {} ({}) with {} (seed {})\n",
             filters::to_string(o.request.model), names, o.request.mode,
             fitness_mode_name(o.request.mode), o.request.solver, o.request.seed);
  print_tune_result(o.baseline_mean, o.tuned_mean, o.tracks, o.param_names, o.params, o.summary,
                    o.divergences.total());
}

SolverSettings solver_of(const TuneArgs& a) {
  SolverSettings s;
  s.solver = a.solver;
  s.seed = a.seed;
  s.particles = a.particles;
  s.iterations = a.iterations;
  s.evaluations = a.evals;
  return s;
}

// Runs `run(req)` with the terminal progress line and Ctrl-C wired into the
// request (the caller keeps `interrupt` to exit 130 after writing results);
// failures become one-line Failures.
template <class Request, class Run>
auto run_with_progress(Request& req, const InterruptGuard& interrupt, Run run) {
  Progress progress("tune", "evaluations");
  req.progress = [&progress](long done, long total) { progress.update(done, total); };
  req.stop = interrupt.flag();
  decltype(run(req)) out;
  try {
    out = run(req);
  } catch (const std::exception& e) {
    throw Failure(e.what());
  }
  progress.finish();
  if (interrupt.raised()) std::fprintf(stderr, "odotune: interrupted; reporting the best so far\n");
  return out;
}

void run_ekf_tune(const TuneArgs& args, filters::NoiseModel model) {
  TuneRequest req;
  static_cast<SolverSettings&>(req) = solver_of(args);
  req.model = model;
  req.mode = args.mode;
  std::string why;
  if (!req.IsValid(&why)) throw Failure(why);

  const std::vector<Track> tracks = load_tracks(args.tracks);
  std::vector<PreparedTrack> prepared;
  for (const auto& t : tracks) {
    try {
      prepared.push_back(prepare_track(t));
    } catch (const std::invalid_argument& e) {
      throw Failure(e.what());
    }
  }
  std::vector<const PreparedTrack*> ptrs;
  for (const auto& p : prepared) ptrs.push_back(&p);

  InterruptGuard interrupt;
  const TuneOutcome out =
      run_with_progress(req, interrupt, [&](const TuneRequest& r) { return run_tune(ptrs, r); });
  print_outcome(out);
  if (!args.json_out.empty())
    write_file_atomically(args.json_out, tune_json(out).dump(2) + "\n");
  if (!args.config_out.empty()) {
    EkfConfig cfg;
    cfg.model = req.model;
    cfg.noise = out.noise;
    cfg.comment = fmt::format("tuned by odotune tune: model {}, mode {}, solver {}, seed {}",
                              args.model, req.mode, req.solver, req.seed);
    write_ekf_config(cfg, args.config_out);
  }
  if (interrupt.raised()) throw Failure("interrupted", 130);
}

void run_calibration_tune_command(const TuneArgs& args, CalibratorModel model) {
  CalibrationTuneRequest req;
  req.model = model;
  if (!filters::parse_resampler(args.resampler, &req.resampler))
    throw Failure(fmt::format("--resampler '{}': expected multinomial, stratified, systematic or residual",
                              args.resampler));
  if (!filters::parse_resample_policy(args.policy, &req.policy))
    throw Failure(fmt::format("--policy '{}': expected every, neff or max", args.policy));
  req.pf_particles = args.pf_particles;
  req.pf_seed = args.pf_seed;
  static_cast<SolverSettings&>(req) = solver_of(args);
  std::string why;
  if (!req.IsValid(&why)) throw Failure(why);
  CalibrationInputOptions input_options;
  input_options.ext_from_gt_rate_hz = args.ext_from_gt_hz;
  if (!input_options.IsValid(&why)) throw Failure("--ext-from-gt: " + why);

  const std::vector<Track> tracks = load_tracks(args.tracks);
  std::vector<CalibrationInput> inputs;
  for (const auto& t : tracks) {
    try {
      inputs.push_back(build_calibration_input(t, input_options));
    } catch (const std::invalid_argument& e) {
      throw Failure(e.what());
    }
    if (!inputs.back().has_gt)
      throw Failure(fmt::format("track '{}': no ground truth (gt_x, gt_y, gt_theta): a calibrator's "
                                "settings are scored by its calibrated odometry against it",
                                t.name()));
  }
  std::vector<const CalibrationInput*> ptrs;
  for (const auto& in : inputs) ptrs.push_back(&in);

  InterruptGuard interrupt;
  const CalibrationTuneOutcome out = run_with_progress(
      req, interrupt, [&](const CalibrationTuneRequest& r) { return run_calibration_tune(ptrs, r); });
  print_calibration_outcome(out);
  if (!args.json_out.empty())
    write_file_atomically(args.json_out,
                          calibration_tune_json(out, {args.ext_from_gt_hz}).dump(2) + "\n");
  if (!args.config_out.empty()) {
    PfConfig cfg;
    CalibrationOptions effective;
    effective.method = calibration_method(model);
    effective.pf = out.tuned_pf;
    const filters::PfCalibratorParams run_with = effective_pf_params(effective);
    cfg.method = effective.method;
    cfg.resampler = run_with.resampler;
    cfg.policy = run_with.policy;
    cfg.particles = run_with.particles;
    cfg.params = out.params;
    cfg.comment = fmt::format(
        "tuned by odotune tune: model {}, solver {}, seed {}, calibrator seed {}; score {:.6g} "
        "(paper's defaults {:.6g})",
        args.model, req.solver, req.seed, req.pf_seed, out.tuned_score, out.baseline_score);
    write_pf_config(cfg, args.config_out);
  }
  if (interrupt.raised()) throw Failure("interrupted", 130);
}

void run_ukf_tune_command(const TuneArgs& args) {
  UkfTuneRequest req;
  static_cast<SolverSettings&>(req) = solver_of(args);
  req.mode = args.mode;
  std::string why;
  if (!req.IsValid(&why)) throw Failure(why);

  const std::vector<Track> tracks = load_tracks(args.tracks);
  std::vector<FusionInput> inputs;
  for (const auto& t : tracks) {
    try {
      inputs.push_back(ukf_fusion_input(t));
    } catch (const std::invalid_argument& e) {
      throw Failure(e.what());
    }
  }
  std::vector<const FusionInput*> ptrs;
  for (const auto& in : inputs) ptrs.push_back(&in);

  InterruptGuard interrupt;
  const UkfTuneOutcome out =
      run_with_progress(req, interrupt, [&](const UkfTuneRequest& r) { return run_ukf_tune(ptrs, r); });
  print_ukf_outcome(out);
  const double rate_hz = 1.0 / inputs.front().dt_s;
  if (!args.json_out.empty()) write_file_atomically(args.json_out, ukf_tune_json(out, rate_hz).dump(2) + "\n");
  if (!args.config_out.empty()) {
    UkfConfig cfg;
    cfg.rate_hz = rate_hz;
    cfg.params = out.params;
    cfg.comment = fmt::format(
        "tuned by odotune tune: model ukf, mode {} ({}), solver {}, seed {}\n"
        "fused pose RMSE {:.2f} mm tuned vs {:.2f} mm with the defaults (mean over {} track{})",
        req.mode, fitness_mode_name(req.mode), req.solver, req.seed, out.tuned_mean.rmse_m * 1e3,
        out.baseline_mean.rmse_m * 1e3, inputs.size(), inputs.size() == 1 ? "" : "s");
    write_ukf_config(cfg, args.config_out);
  }
  if (interrupt.raised()) throw Failure("interrupted", 130);
}

}  // namespace

void register_tune(CLI::App& app) {
  auto args = std::make_shared<TuneArgs>();
  auto* sub = app.add_subcommand(
      "tune",
      "Tune the EKF noise of one model, a particle-filter calibrator's settings, or the fusion UKF's "
      "noise, on tracks");
  sub->footer(
      "Example:\n"
      "  odotune tune --track data/tracks/track1.csv --model rq --mode 7 --seed 1 --json out.json\n"
      "  odotune tune --track a.csv --track b.csv --model gyro --solver nlopt:DIRECT_L --evals 3000\n"
      "  odotune tune --track wheelchair.csv --model adaptive-pf-calib --particles 16 --iterations 10 \\\n"
      "      --config-out pf.yaml\n"
      "EKF models: prints baseline and tuned RMSE/MAE/MAXE with the improvement in %. The baseline\n"
      "is the untuned configuration described in the README (alpha model, α1 = α2 = 0.01, σ_fix 60 mm).\n"
      "Calibrators (pf-calib, adaptive-pf-calib): tunes N_eff fraction, max-weight ratio, α,\n"
      "dispersion per particle and random-walk σ; the score weighs the final radius error,\n"
      "convergence time, the calibrated odometry's pose RMSE and the particle count\n"
      "(objectives/calibration_objective.h). The baseline is the paper's default settings;\n"
      "if they score better than the solver's best they are kept. Tracks need external velocities\n"
      "(v_ext, w_ext, or --ext-from-gt HZ) and ground truth, all of one robot. --config-out writes\n"
      "an odotune-pf-config/1 file (formats/pf_config_yaml.h).\n"
      "UKF (ukf): tunes the (V, W) fusion filter's process noise, static odometry variances, gyro\n"
      "variance and external-variance scale (objectives/ukf_objective.h) for --mode's error of\n"
      "the fused pose against ground truth (tracks need it); the baseline is the default noise.\n"
      "--config-out writes an odotune-ukf-config/1 file (formats/ukf_config_yaml.h).");
  sub->add_option("--track", args->tracks, "track file (repeat for several; fitness = mean over tracks)")
      ->required();
  sub->add_option("--model", args->model, "rq | alpha | gyro | pf-calib | adaptive-pf-calib | ukf");
  sub->add_option("--mode", args->mode,
                  "EKF/UKF fitness mode: 1 RMSE, 2 MAE, 3 MAXE, 4 RMSE+MAE, 5 RMSE+MAXE, 6 MAE+MAXE, "
                  "7 RMSE+MAE+MAXE")
      ->check(CLI::Range(1, 7));
  std::string algos;
  for (const auto& a : tuner::nlopt_algorithm_names()) algos += " " + a;
  sub->add_option("--solver", args->solver, "pso or nlopt:NAME, NAME one of" + algos);
  sub->add_option("--seed", args->seed, "random seed (same seed ⇒ same result)");
  sub->add_option("--particles", args->particles, "PSO swarm size")->check(CLI::PositiveNumber);
  sub->add_option("--iterations", args->iterations, "PSO iterations")->check(CLI::NonNegativeNumber);
  sub->add_option("--evals", args->evals,
                  "NLopt evaluation budget (default: particles × (iterations + 1), as PSO)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--json", args->json_out, "write the result as JSON to this file");
  sub->add_option("--config-out", args->config_out,
                  "write the tuned configuration (YAML: EKF models for eval --config, calibrators "
                  "odotune-pf-config/1, ukf odotune-ukf-config/1)");
  sub->add_option("--resampler", args->resampler,
                  "calibrators: multinomial | stratified | systematic | residual (default systematic)");
  sub->add_option("--policy", args->policy, "calibrators: resampling policy every | neff | max (default neff)");
  sub->add_option("--pf-particles", args->pf_particles,
                  "calibrators: N (pf-calib) or initial N (adaptive-pf-calib); default the paper's "
                  "5000 / 8000")
      ->check(CLI::PositiveNumber);
  sub->add_option("--pf-seed", args->pf_seed, "calibrators: the particle filter's own seed (default 1)");
  sub->add_option("--ext-from-gt", args->ext_from_gt_hz,
                  "calibrators: derive the external velocities from the ground truth at this rate [Hz] "
                  "instead of the tracks' v_ext/w_ext")
      ->check(CLI::PositiveNumber);
  add_threads_option(sub, &args->threads);

  sub->callback([args, sub] {
    apply_threads(args->threads);
    TunedModel model;
    if (!parse_tuned_model(args->model, &model))
      throw Failure(fmt::format("--model '{}': unknown model, expected {}", args->model, tuned_model_names()));
    for (const std::string& opt : model.calibrator ? kEkfOnly : kCalibratorOnly)
      if (sub->count(opt) > 0)
        throw Failure(fmt::format("{} applies to {} models only, not to --model {}", opt,
                                  model.calibrator ? "the EKF and UKF (rq, alpha, gyro, ukf)" : "the calibrator",
                                  args->model));
    if (model.calibrator)
      run_calibration_tune_command(*args, model.calib);
    else if (model.ukf)
      run_ukf_tune_command(*args);
    else
      run_ekf_tune(*args, model.noise);
  });
}

}  // namespace odotune::cli

// odotune tune: tune one noise model on one or more tracks.
#include <cstdio>
#include <fstream>
#include <iostream>

#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/config_yaml.h"
#include "cli/failure.h"
#include "cli/output.h"
#include "cli/progress.h"
#include "cli/tune_job.h"
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
};

void print_outcome(const TuneOutcome& o) {
  std::string names;
  for (const auto& t : o.tracks) names += (names.empty() ? "" : ", ") + t.track;
  fmt::print("tuned {} noise on {} for mode {} ({}) with {} (seed {})\n",
             filters::to_string(o.request.model), names, o.request.mode,
             fitness_mode_name(o.request.mode), o.request.solver, o.request.seed);
  fmt::print("  RMSE {}\n", metric_change(o.baseline_mean.rmse_m, o.tuned_mean.rmse_m));
  fmt::print("  MAE  {}\n", metric_change(o.baseline_mean.mae_m, o.tuned_mean.mae_m));
  fmt::print("  MAXE {}\n", metric_change(o.baseline_mean.maxe_m, o.tuned_mean.maxe_m));
  if (o.tracks.size() > 1)
    for (const auto& t : o.tracks)
      fmt::print("    {}: RMSE {}\n", t.track, metric_change(t.baseline.rmse_m, t.tuned.rmse_m));
  fmt::print("  params:");
  for (std::size_t i = 0; i < o.params.size(); ++i)
    fmt::print(" {}={:.6g}", o.param_names[i], o.params[i]);
  fmt::print("\n  {} evaluations in {:.2f} s ({}); diverged evaluations: {}\n",
             o.summary.evaluations, o.summary.seconds, o.summary.termination,
             o.divergences.total());
}

}  // namespace

void register_tune(CLI::App& app) {
  auto args = std::make_shared<TuneArgs>();
  auto* sub = app.add_subcommand("tune", "Tune the EKF noise of one model on one or more tracks");
  sub->footer(
      "Example:\n"
      "  odotune tune --track data/tracks/track1.csv --model rq --mode 7 --seed 1 --json out.json\n"
      "  odotune tune --track a.csv --track b.csv --model gyro --solver nlopt:DIRECT_L --evals 3000\n"
      "Prints baseline and tuned RMSE/MAE/MAXE with the improvement in %. The baseline is the\n"
      "untuned configuration described in the README (alpha model, α1 = α2 = 0.01, σ_fix 60 mm).");
  sub->add_option("--track", args->tracks, "track file (repeat for several; fitness = mean over tracks)")
      ->required();
  sub->add_option("--model", args->model, "noise model: rq | alpha | gyro")
      ->check(CLI::IsMember({"rq", "alpha", "gyro"}));
  sub->add_option("--mode", args->mode,
                  "fitness mode: 1 RMSE, 2 MAE, 3 MAXE, 4 RMSE+MAE, 5 RMSE+MAXE, 6 MAE+MAXE, "
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
                  "write the tuned configuration (YAML, read by eval --config)");
  add_threads_option(sub, &args->threads);

  sub->callback([args] {
    apply_threads(args->threads);
    TuneRequest req;
    filters::parse_noise_model(args->model, &req.model);
    req.mode = args->mode;
    req.solver = args->solver;
    req.seed = args->seed;
    req.particles = args->particles;
    req.iterations = args->iterations;
    req.evaluations = args->evals;
    std::string why;
    if (!req.IsValid(&why)) throw Failure(why);

    const std::vector<Track> tracks = load_tracks(args->tracks);
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
    Progress progress("tune", "evaluations");
    req.progress = [&progress](long done, long total) { progress.update(done, total); };
    req.stop = interrupt.flag();
    TuneOutcome out;
    try {
      out = run_tune(ptrs, req);
    } catch (const std::exception& e) {
      throw Failure(e.what());
    }
    progress.finish();
    if (interrupt.raised()) std::fprintf(stderr, "odotune: interrupted; reporting the best so far\n");
    print_outcome(out);
    if (!args->json_out.empty())
      write_file_atomically(args->json_out, tune_json(out).dump(2) + "\n");
    if (!args->config_out.empty()) {
      EkfConfig cfg;
      cfg.model = req.model;
      cfg.noise = out.noise;
      cfg.comment = fmt::format("tuned by odotune tune: model {}, mode {}, solver {}, seed {}",
                                args->model, req.mode, req.solver, req.seed);
      write_ekf_config(cfg, args->config_out);
    }
    if (interrupt.raised()) throw Failure("interrupted", 130);
  });
}

}  // namespace odotune::cli

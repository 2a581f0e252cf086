// odotune demo: the README's main job. The five bundled reference tracks ×
// the three noise models, tuned by PSO for fitness mode 7, as a table of
// baseline vs tuned errors (odotune/jobs/demo_job.h).
#include <cstdio>
#include <optional>

#include <fmt/format.h>

#include <odotune/cli/commands.h>
#include <odotune/cli/output.h>
#include <odotune/cli/progress.h>
#include <odotune/jobs/demo_job.h>

namespace odotune::cli {

void register_demo(CLI::App& app) {
  auto req = std::make_shared<jobs::DemoRequest>();
  req->data_dir = std::string(ODOTUNE_SOURCE_DIR) + "/data/tracks";
  auto threads = std::make_shared<int>(0);
  auto* sub = app.add_subcommand("demo",
                                 "Tune the three noise models on the five bundled reference tracks (mode 7)");
  sub->footer("Example:\n"
              "  odotune demo                       # PSO 50 × 150, seed 1, as in the study\n"
              "  odotune demo --iterations 30 --json demo.json");
  sub->add_option("--data", req->data_dir, "folder with track1.csv … track5.csv");
  sub->add_option("--particles", req->particles, "PSO swarm size")->check(CLI::PositiveNumber);
  sub->add_option("--iterations", req->iterations, "PSO iterations")->check(CLI::NonNegativeNumber);
  add_fitness_mode_option(
      sub, [req](objectives::FitnessMode m) { req->mode = m; },
      "fitness mode 1..7, number or name (default 7, rmse+mae+maxe)",
      /*ground_truth_only=*/true);
  sub->add_option("--seed", req->seed, "random seed");
  sub->add_option("--json", req->json_out, "write all results as JSON to this file");
  add_threads_option(sub, threads.get());
  sub->callback([req, threads] {
    apply_threads(*threads);
    std::optional<InterruptGuard> interrupt;
    std::optional<Progress> progress;
    jobs::DemoCallbacks cb;
    cb.started = [&] {
      fmt::print("odotune demo: EKF noise tuned by PSO ({} particles × {} iterations, seed {}), "
                 "fitness mode {} ({})\n",
                 req->particles, req->iterations, req->seed, objectives::number(req->mode),
                 objectives::fitness_mode_name(req->mode));
      fmt::print("baseline: alpha noise α1 = α2 = 0.01, fixes σ = 60 mm (see README)\n\n");
      fmt::print("{:<8} {:<6} {:>33} {:>33} {:>33}\n", "track", "model", "RMSE baseline → tuned",
                 "MAE baseline → tuned", "MAXE baseline → tuned");
      interrupt.emplace();
      progress.emplace("demo", "tunes");
      return interrupt->flag();
    };
    cb.tune_started = [&](const std::string& label, long done, long total) {
      progress->set_label(label);
      progress->update(done, total);
    };
    cb.row = [&](const jobs::DemoRow& r, long done, long total) {
      progress->finish();
      const objectives::ErrorMetrics &b = r.outcome.baseline_mean, &t = r.outcome.tuned_mean;
      fmt::print("{:<8} {:<6} {:>33} {:>33} {:>33}\n", r.track, filters::to_string(r.model),
                 metric_change(b.rmse_m, t.rmse_m), metric_change(b.mae_m, t.mae_m),
                 metric_change(b.maxe_m, t.maxe_m));
      std::fflush(stdout);
      progress->update(done, total);
    };
    cb.finished = [&](const jobs::DemoOutcome& o) {
      progress->finish();
      fmt::print("\n{} tunes, {} evaluations each, {:.1f} s of optimisation in all\n", o.rows.size(),
                 o.evaluations_per_tune, o.seconds);
    };
    jobs::run_demo(*req, cb);
  });
}

}  // namespace odotune::cli

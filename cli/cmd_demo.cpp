// odotune demo: the README's main job. The five bundled reference tracks ×
// the three noise models, tuned by PSO for fitness mode 7, as a table of
// baseline vs tuned errors.
#include <filesystem>

#include <fmt/format.h>

#include "cli/commands.h"
#include "formats/config_yaml.h"
#include "core/failure.h"
#include "cli/output.h"
#include "tracks/track_io.h"
#include "jobs/tune_json.h"
#include "cli/progress.h"
#include "jobs/tune_job.h"

namespace odotune::cli {

namespace {
struct DemoArgs {
  std::string data_dir = std::string(ODOTUNE_SOURCE_DIR) + "/data/tracks";
  int particles = 50, iterations = 150, mode = 7;
  std::uint64_t seed = 1;
  std::string json_out;
  int threads = 0;
};
}  // namespace

void register_demo(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  auto* sub = app.add_subcommand(
      "demo", "Tune the three noise models on the five bundled reference tracks (mode 7)");
  sub->footer(
      "Example:\n"
      "  odotune demo                       # PSO 50 × 150, seed 1, as in the study\n"
      "  odotune demo --iterations 30 --json demo.json");
  sub->add_option("--data", args->data_dir, "folder with track1.csv … track5.csv");
  sub->add_option("--particles", args->particles, "PSO swarm size")->check(CLI::PositiveNumber);
  sub->add_option("--iterations", args->iterations, "PSO iterations")->check(CLI::NonNegativeNumber);
  sub->add_option("--mode", args->mode, "fitness mode 1..7")->check(CLI::Range(1, 7));
  sub->add_option("--seed", args->seed, "random seed");
  sub->add_option("--json", args->json_out, "write all results as JSON to this file");
  add_threads_option(sub, &args->threads);
  sub->callback([args] {
    apply_threads(args->threads);
    std::vector<std::string> paths;
    for (int i = 1; i <= 5; ++i) {
      const auto p = std::filesystem::path(args->data_dir) / fmt::format("track{}.csv", i);
      if (!std::filesystem::exists(p))
        throw Failure(fmt::format("{}: reference track not found (use --data DIR)", p.string()));
      paths.push_back(p.string());
    }
    const std::vector<Track> tracks = load_tracks(paths);
    std::vector<PreparedTrack> prepared;
    for (const auto& t : tracks) prepared.push_back(prepare_track(t));

    const filters::NoiseModel models[] = {filters::NoiseModel::rq, filters::NoiseModel::alpha,
                                          filters::NoiseModel::gyro};
    fmt::print("odotune demo: EKF noise tuned by PSO ({} particles × {} iterations, seed {}), "
               "fitness mode {} ({})\n",
               args->particles, args->iterations, args->seed, args->mode,
               fitness_mode_name(args->mode));
    fmt::print("baseline: alpha noise α1 = α2 = 0.01, fixes σ = 60 mm (see README)\n\n");
    fmt::print("{:<8} {:<6} {:>33} {:>33} {:>33}\n", "track", "model", "RMSE baseline → tuned",
               "MAE baseline → tuned", "MAXE baseline → tuned");

    InterruptGuard interrupt;
    Progress progress("demo", "tunes");
    nlohmann::json all = nlohmann::json::array();
    const long total = static_cast<long>(prepared.size()) * 3;
    long done = 0;
    double seconds = 0;
    for (const auto& p : prepared) {
      for (auto model : models) {
        progress.set_label(fmt::format("demo {} {}", p.name, filters::to_string(model)));
        progress.update(done, total);
        TuneRequest req;
        req.model = model;
        req.mode = args->mode;
        req.seed = args->seed;
        req.particles = args->particles;
        req.iterations = args->iterations;
        req.stop = interrupt.flag();
        const TuneOutcome o = run_tune({&p}, req);
        progress.finish();
        if (interrupt.raised()) throw Failure("interrupted", 130);
        seconds += o.summary.seconds;
        const auto& b = o.baseline_mean;
        const auto& t = o.tuned_mean;
        fmt::print("{:<8} {:<6} {:>33} {:>33} {:>33}\n", p.name, filters::to_string(model),
                   metric_change(b.rmse_m, t.rmse_m), metric_change(b.mae_m, t.mae_m),
                   metric_change(b.maxe_m, t.maxe_m));
        std::fflush(stdout);
        all.push_back(tune_json(o));
        progress.update(++done, total);
      }
    }
    progress.finish();
    fmt::print("\n{} tunes, {} evaluations each, {:.1f} s of optimisation in all\n", total,
               static_cast<long>(args->particles) * (args->iterations + 1), seconds);
    if (!args->json_out.empty()) write_file_atomically(args->json_out, all.dump(2) + "\n");
  });
}

}  // namespace odotune::cli

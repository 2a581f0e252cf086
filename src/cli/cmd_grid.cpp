// odotune grid: run an experiment grid into a crash-safe results store.
#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/failure.h"
#include "cli/grid_job.h"
#include "cli/output.h"
#include "cli/progress.h"

namespace odotune::cli {

namespace {
struct GridArgs {
  std::string experiment, store;
  bool allow_other = false;
  int threads = 0;
};
}  // namespace

void register_grid(CLI::App& app) {
  auto args = std::make_shared<GridArgs>();
  auto* sub = app.add_subcommand(
      "grid", "Run an experiment grid (models × tracks × modes × seeds) into a results store");
  sub->footer(
      "Example:\n"
      "  odotune grid experiments/smoke.yaml                 # a minute or two\n"
      "  odotune grid experiments/study.yaml --store night.sqlite\n"
      "Killed or interrupted, the same command continues where it stopped: finished runs are\n"
      "never repeated or lost, and the results equal an uninterrupted run's.");
  sub->add_option("experiment", args->experiment, "experiment YAML (format odotune-experiment/1)")
      ->required();
  sub->add_option("--store", args->store, "results store (SQLite); overrides the file's 'store'");
  sub->add_flag("--allow-other-experiment", args->allow_other,
                "continue into a store made from a different experiment file");
  add_threads_option(sub, &args->threads);
  sub->callback([args] {
    apply_threads(args->threads);
    const Experiment e = read_experiment(args->experiment);
    const std::filesystem::path store_path = args->store.empty() ? e.store : std::filesystem::path(args->store);
    std::unique_ptr<results::Store> store;
    try {
      if (store_path.has_parent_path()) std::filesystem::create_directories(store_path.parent_path());
      store = std::make_unique<results::Store>(
          store_path,
          results::ExperimentInfo{e.name, e.text, results::experiment_hash(e.text), ODOTUNE_VERSION,
                                  std::filesystem::absolute(e.file).lexically_normal().string()},
          args->allow_other);
    } catch (const std::filesystem::filesystem_error& ex) {
      throw Failure(fmt::format("{}: cannot create the store's folder: {}", store_path.string(),
                                ex.code().message()));
    } catch (const std::runtime_error& ex) {
      throw Failure(ex.what());
    }
    InterruptGuard interrupt;
    Progress progress("grid " + e.name, "runs");
    const GridOutcome o = run_grid(e, *store, interrupt.flag(),
                                   [&progress](long done, long total) { progress.update(done, total); });
    progress.finish();
    fmt::print("{}: {} runs in the experiment, {} already stored, {} run now{}\n",
               store_path.string(), o.total, o.skipped, o.ran,
               o.abandoned ? fmt::format(", {} abandoned", o.abandoned) : "");
    if (interrupt.raised())
      throw Failure("interrupted; run the same command to continue where it stopped", 130);
  });
}

}  // namespace odotune::cli

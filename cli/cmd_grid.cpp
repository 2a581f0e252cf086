// odotune grid: run an experiment grid into a crash-safe results store.
#include <fmt/format.h>

#include "cli/commands.h"
#include "core/failure.h"
#include "jobs/grid_job.h"
#include "jobs/grid_mpi.h"
#include "cli/output.h"
#include "cli/progress.h"

namespace odotune::cli {

namespace {
struct GridArgs {
  std::string experiment, store;
  bool allow_other = false;
  int threads = 0;
};

// Opens (or creates, folder included) the experiment's store. Throws Failure.
std::unique_ptr<results::Store> open_store(const Experiment& e, const std::filesystem::path& path,
                                          bool allow_other) {
  try {
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    return std::make_unique<results::Store>(
        path,
        results::ExperimentInfo{e.name, e.text, results::experiment_hash(e.text), ODOTUNE_VERSION,
                                std::filesystem::absolute(e.file).lexically_normal().string()},
        allow_other);
  } catch (const std::filesystem::filesystem_error& ex) {
    throw Failure(fmt::format("{}: cannot create the store's folder: {}", path.string(),
                              ex.code().message()));
  } catch (const std::runtime_error& ex) {
    throw Failure(ex.what());
  }
}
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
      "never repeated or lost, and the results equal an uninterrupted run's.\n" +
      std::string(mpi_built()
                      ? "MPI: built in. `mpirun -np N odotune grid ...` shares the runs over N ranks\n"
                        "(rank 0 writes the store); the results equal a one-process run's."
                      : "MPI: not built in (configure with -DODOTUNE_WITH_MPI=ON to share a grid over\n"
                        "the nodes of a cluster with mpirun)."));
  sub->add_option("experiment", args->experiment, "experiment YAML (format odotune-experiment/1)")
      ->required();
  sub->add_option("--store", args->store, "results store (SQLite); overrides the file's 'store'");
  sub->add_flag("--allow-other-experiment", args->allow_other,
                "continue into a store made from a different experiment file");
  add_threads_option(sub, &args->threads);
  sub->callback([args] {
    apply_threads(args->threads);
    // Under mpirun/srun (MPI build): the ranks share the cells, rank 0 alone
    // writes the store and prints; a failure anywhere is told once, by rank 0.
    const MpiSession mpi;
    Experiment e;
    if (!mpi.agree([&] { e = read_experiment(args->experiment); })) return;
    const std::filesystem::path store_path = args->store.empty() ? e.store : std::filesystem::path(args->store);
    std::unique_ptr<results::Store> store;
    if (!mpi.agree([&] {
          if (mpi.rank() == 0) store = open_store(e, store_path, args->allow_other);
        }))
      return;
    InterruptGuard interrupt;
    Progress progress("grid " + e.name, "runs");
    const auto update = [&progress](long done, long total) { progress.update(done, total); };
    GridOutcome o;
    if (mpi.size() > 1) {
      const auto ranked = run_grid_mpi(mpi, e, store.get(), interrupt.flag(), update);
      if (!ranked) return;  // not rank 0: rank 0 reports
      o = *ranked;
    } else {
      o = run_grid(e, *store, interrupt.flag(), update);
    }
    progress.finish();
    fmt::print("{}: {} runs in the experiment, {} already stored, {} run now{}{}\n",
               store_path.string(), o.total, o.skipped, o.ran,
               o.abandoned ? fmt::format(", {} abandoned", o.abandoned) : "",
               mpi.size() > 1 ? fmt::format(" (on {} MPI ranks)", mpi.size()) : "");
    if (interrupt.raised())
      throw Failure("interrupted; run the same command to continue where it stopped", 130);
  });
}

}  // namespace odotune::cli

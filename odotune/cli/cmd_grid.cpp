// odotune grid: run an experiment grid into a crash-safe results store
// (odotune/jobs/grid_mpi.h, run_grid_job).
#include <optional>

#include <fmt/format.h>

#include <odotune/cli/commands.h>
#include <odotune/cli/output.h>
#include <odotune/cli/progress.h>
#include <odotune/core/failure.h>
#include <odotune/jobs/grid_mpi.h>

namespace odotune::cli {

void register_grid(CLI::App& app) {
  auto req = std::make_shared<jobs::GridRequest>();
  req->code_version = ODOTUNE_VERSION;
  auto threads = std::make_shared<int>(0);
  auto* sub = app.add_subcommand(
      "grid", "Run an experiment grid (models × tracks × modes × seeds) into a results store");
  sub->footer("Example:\n"
              "  odotune grid experiments/smoke.yaml                 # a minute or two\n"
              "  odotune grid experiments/study.yaml --store night.sqlite\n"
              "Killed or interrupted, the same command continues where it stopped: finished runs are\n"
              "never repeated or lost, and the results equal an uninterrupted run's.\n" +
              std::string(jobs::mpi_built()
                              ? "MPI: built in. `mpirun -np N odotune grid ...` shares the runs over N ranks\n"
                                "(rank 0 writes the store); the results equal a one-process run's."
                              : "MPI: not built in (configure with -DODOTUNE_WITH_MPI=ON to share a grid over\n"
                                "the nodes of a cluster with mpirun)."));
  sub->add_option("experiment", req->experiment, "experiment YAML (format odotune-experiment/1)")->required();
  sub->add_option("--store", req->store, "results store (SQLite); overrides the file's 'store'");
  sub->add_flag("--allow-other-experiment", req->allow_other,
                "continue into a store made from a different experiment file");
  add_threads_option(sub, threads.get());
  sub->callback([req, threads] {
    apply_threads(*threads);
    std::optional<InterruptGuard> interrupt;
    std::optional<Progress> progress;
    jobs::GridCallbacks cb;
    cb.started = [&](const formats::Experiment& e) {
      interrupt.emplace();
      progress.emplace("grid " + e.name, "runs");
      return interrupt->flag();
    };
    cb.progress = [&](long done, long total) { progress->update(done, total); };
    const std::optional<jobs::GridReport> r = jobs::run_grid_job(*req, cb);
    if (!r) return;  // not rank 0 (MPI): rank 0 reports
    progress->finish();
    const jobs::GridOutcome& o = r->outcome;
    fmt::print("{}: {} runs in the experiment, {} already stored, {} run now{}{}\n", r->store.string(), o.total,
               o.skipped, o.ran, o.abandoned ? fmt::format(", {} abandoned", o.abandoned) : "",
               r->ranks > 1 ? fmt::format(" (on {} MPI ranks)", r->ranks) : "");
    if (interrupt->raised())
      throw core::Failure("interrupted; run the same command to continue where it stopped", 130);
  });
}

}  // namespace odotune::cli

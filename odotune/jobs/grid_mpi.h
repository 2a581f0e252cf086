// MPI for `odotune grid` (built with -DODOTUNE_WITH_MPI=ON; see README, "MPI").
//
// The same binary started N times by an MPI launcher (`mpirun -np N`, or
// Slurm's `srun`) shards the grid's cells over the N ranks. Every rank reads
// the experiment and its tracks and computes the same cell list; rank 0 alone
// opens the results store, finds the cells still to run and hands them out one
// at a time to whichever rank asks (its own OpenMP threads included); the
// other ranks send each finished run to rank 0, which writes it in its own
// transaction as it arrives. A run's numbers do not depend on which rank or
// thread computes it, so the store ends identical to a one-process run, and a
// killed job resumes like a one-process one.
//
// Errors: a failure on any rank ends the job on every rank, and rank 0 prints
// it as one line ("rank R: ..."); the other ranks print nothing and exit 0
// (mpirun exits with rank 0's code).
//
// Without MPI built in, or not started by a launcher, none of this runs: the
// session has one rank and the grid runs in-process as before.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include <odotune/formats/experiment_yaml.h>
#include <odotune/jobs/grid_job.h>
#include <odotune/results/store.h>

namespace odotune::jobs {

// Whether this binary was built with MPI.
bool mpi_built();

// MPI for the lifetime of one command. Initialised (MPI_THREAD_SERIALIZED)
// only in an MPI build started by an MPI launcher; finalised when it goes.
// Throws Failure when MPI cannot be started, or when a build without MPI is
// started as one of several ranks (each would run the whole grid).
class MpiSession {
 public:
  MpiSession();
  ~MpiSession();  // NOLINT(performance-trivially-destructible): MPI_Finalize in an MPI build
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }

  // Runs `step` on every rank (a collective call). With one rank it just runs
  // it. With several: if it threw on none, returns true; if it threw on any,
  // rank 0 throws Failure with the first failure's line (prefixed "rank R: "
  // when it is another rank's) and the other ranks return false.
  bool agree(const std::function<void()>& step) const;

 private:
  int rank_ = 0, size_ = 1;
  bool initialised_ = false;
};

// The grid over all ranks of `mpi` (size > 1; a collective call). `store`
// is used on rank 0 only (null elsewhere); `progress(done, total)` is called on
// rank 0 only, one call at a time. Returns the outcome on rank 0 and nothing on
// the other ranks. Throws Failure on rank 0 when any rank failed.
std::optional<GridOutcome> run_grid_mpi(const MpiSession& mpi, const formats::Experiment& e,
                                        results::Store* store, const std::atomic<bool>* stop,
                                        const std::function<void(long, long)>& progress);

// `odotune grid` as one call, with or without MPI.
struct GridRequest {
  std::string experiment;    // experiment YAML (odotune-experiment/1)
  std::string store;         // results store; empty = the experiment's `store`
  bool allow_other = false;  // continue into a store made from another experiment file
  std::string code_version;  // odotune version recorded in a new store
};

// Where the command hears of the grid (each may be empty).
struct GridCallbacks {
  // On every rank, once the experiment is read and the store opened, before
  // the first cell. Returns the flag that stops the grid when raised (null:
  // never stopped).
  std::function<const std::atomic<bool>*(const formats::Experiment&)> started;
  // progress(done, total): rank 0 only, one call at a time.
  std::function<void(long, long)> progress;
};

struct GridReport {
  std::filesystem::path store;  // the store written
  GridOutcome outcome;
  int ranks = 1;  // MPI ranks that shared the cells
};

// Starts an MpiSession for the call (finalised before it returns); on every
// rank reads the experiment, on rank 0 opens (or creates) the store
// (open_grid_store), then runs the cells the store lacks: over the ranks with
// run_grid_mpi when started as several, else in-process with run_grid. A
// stopped grid returns normally (the outcome counts the runs abandoned).
// Returns the report on rank 0 and nothing on the other ranks (rank 0
// reports, a failure included).
// Throws core::Failure (one line) when MPI cannot be started (MpiSession),
// and on rank 0 on an unreadable experiment, a store that cannot be opened, a
// bad track or a solver failure.
std::optional<GridReport> run_grid_job(const GridRequest& request, const GridCallbacks& callbacks);

}  // namespace odotune::jobs

// The experiment grid: every cell (model × track × mode × seed, and the
// leave-one-track-out cells) tuned and written to the results store.
// Computation only (the grid command prints). Cells run in parallel with
// OpenMP (each tune then runs its swarm on one thread); results do not depend
// on the thread count, so a resumed grid ends identical to an uninterrupted one.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "cli/experiment_yaml.h"
#include "results/run_record.h"
#include "results/store.h"

namespace odotune::cli {

struct GridCell {
  filters::NoiseModel model;
  std::vector<std::size_t> tune_on;  // indices into the experiment's tracks
  std::size_t score_on;              // index of the track the scores are for
  bool heldout = false;              // leave-one-track-out cell
  int mode;
  std::uint64_t seed;
};

// The cells of an experiment, in a fixed order.
std::vector<GridCell> grid_cells(const Experiment& e);

struct GridOutcome {
  long total = 0;     // cells in the experiment
  long skipped = 0;   // already in the store
  long ran = 0;       // finished and written now
  long abandoned = 0; // in flight when stopped, not written
};

// Runs the cells the store does not have yet. `progress(done, total)` is
// called from one thread at a time. Throws odotune::cli::Failure on a bad
// track or a solver failure.
GridOutcome run_grid(const Experiment& e, results::Store& store, const std::atomic<bool>* stop,
                     const std::function<void(long, long)>& progress);

}  // namespace odotune::cli

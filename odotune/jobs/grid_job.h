// The experiment grid: every cell (model × track × mode × seed, and the
// leave-one-track-out cells) tuned and written to the results store. A
// calibrator model (pf-calib, adaptive-pf-calib) has cells for the first
// listed mode only (it has no fitness mode; experiment_yaml.h).
// Computation only (the grid command prints). Cells run in parallel with
// OpenMP (each tune then runs its swarm on one thread); results do not depend
// on the thread count, so a resumed grid ends identical to an uninterrupted one.
// Under MPI, odotune/jobs/grid_mpi.h shares the cells over processes with the same
// pieces (run_cell, work_cells).
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <odotune/formats/experiment_yaml.h>
#include <odotune/jobs/tune_job.h>
#include <odotune/results/run_record.h>
#include <odotune/results/store.h>

namespace odotune::jobs {

// What a cell minimises: a fitness mode, or (model rl-ekf) one of
// robot_localization's fitnesses.
using CellFitness = std::variant<objectives::FitnessMode, objectives::RlFitness>;
// The mode number a results store records for it (odotune/results/run_record.h).
int stored_mode(const CellFitness& f);

struct GridCell {
  objectives::TunedModel model;
  std::vector<std::size_t> tune_on;  // indices into the experiment's tracks
  std::size_t score_on;              // index of the track the scores are for
  bool heldout = false;              // leave-one-track-out cell
  CellFitness fitness;
  std::uint64_t seed;
};

// The cells of an experiment, in a fixed order.
std::vector<GridCell> grid_cells(const formats::Experiment& e);

struct GridOutcome {
  long total = 0;      // cells in the experiment
  long skipped = 0;    // already in the store
  long ran = 0;        // finished and written now
  long abandoned = 0;  // in flight when stopped, not written
};

// The experiment's tracks, read and prepared for the listed models: for
// replay when an EKF model is listed, as calibration input (with the
// experiment's calibration.ext_from_gt_hz) when a calibrator model is, as
// fusion input (ukf_tune_job.h) when the ukf model is.
// Throws core::Failure (one line naming the track) when a track is
// unusable for a listed model.
std::vector<PreparedTrack> prepare_grid_tracks(const formats::Experiment& e);

// The record of a cell without its results: what identifies it in the store
// (results::run_key).
results::RunRecord cell_record(const formats::Experiment& e, const std::vector<PreparedTrack>& tracks,
                               const GridCell& c);

// Indices (into `cells`) of the cells whose run the store does not have yet,
// in cell order.
std::vector<std::size_t> pending_cells(const formats::Experiment& e, const std::vector<PreparedTrack>& tracks,
                                       const std::vector<GridCell>& cells, const results::Store& store);

// Tunes one cell and scores it. An EKF cell's scores are the reference
// replay's position errors with the baseline and the tuned noise; a
// calibrator cell's (calibration_tune_job.h) are the dead-reckoning position
// errors of the calibrated odometry with the paper's default and the tuned
// settings on the scored track, its params the tuned settings and its
// best_fitness the tuned score; a ukf cell's (ukf_tune_job.h) are the fused
// pose's position errors with the default and the tuned UKF noise. The result depends only on the experiment,
// the tracks and the cell (not on the thread, process or machine that runs it).
// Returns nothing when `stop` ended the run early (there is nothing to keep).
// Throws std::exception when the solver fails.
std::optional<results::RunRecord> run_cell(const formats::Experiment& e,
                                           const std::vector<PreparedTrack>& tracks, const GridCell& c,
                                           const std::atomic<bool>* stop);

// Where a worker gets cells and leaves finished runs. Both functions are
// called by one thread at a time. `next` returns an index into the cells, or
// nothing when there is no more work; `finished` keeps a run (throwing makes
// it the failure).
struct CellSource {
  std::function<std::optional<std::size_t>()> next;
  std::function<void(results::RunRecord&&)> finished;
  // Optional: told the first failure's line as soon as it happens.
  std::function<void(const std::string&)> failed;
};

struct WorkResult {
  long ran = 0;         // runs handed to `finished`
  long abandoned = 0;   // runs that `stop` ended early
  std::string failure;  // the first failure, one line; empty if none
};

// Runs cells from `source` on all OpenMP threads (one cell per thread at a
// time) until it has no more, `stop` is raised, or a run fails; then waits for
// the runs in flight. Never throws: a failure is returned.
WorkResult work_cells(const formats::Experiment& e, const std::vector<PreparedTrack>& tracks,
                      const std::vector<GridCell>& cells, const CellSource& source,
                      const std::atomic<bool>* stop);

// Opens the experiment's results store at `path`, or creates it (and its
// folder) recording the experiment's name, text, hash, absolute file path and
// `code_version` (the odotune version). A store made from another experiment
// is refused unless `allow_other`. Throws core::Failure (one line).
std::unique_ptr<results::Store> open_grid_store(const formats::Experiment& e, const std::filesystem::path& path,
                                                bool allow_other, const std::string& code_version);

// Runs the cells the store does not have yet. `progress(done, total)` is
// called from one thread at a time. Throws core::Failure on a bad
// track or a solver failure.
GridOutcome run_grid(const formats::Experiment& e, results::Store& store, const std::atomic<bool>* stop,
                     const std::function<void(long, long)>& progress);

}  // namespace odotune::jobs

// `odotune demo`, the README's main job: the five bundled reference tracks ×
// the three EKF noise models (rq, alpha, gyro), each tuned by PSO on its own
// track, one table row per tune. Computation and file output only; the
// command prints the table as the rows arrive.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <odotune/filters/ekf_noise.h>
#include <odotune/jobs/tune_job.h>

namespace odotune::jobs {

struct DemoRequest {
  std::string data_dir;                                            // folder with track1.csv … track5.csv
  int particles = 50, iterations = 150;                            // PSO budget of each tune
  objectives::FitnessMode mode = objectives::kDefaultFitnessMode;  // against ground truth (1..7)
  std::uint64_t seed = 1;
  std::string json_out;  // every tune's tune_json() as one JSON array; empty = not written
};

// One row of the demo's table: a model tuned on a track.
struct DemoRow {
  std::string track;
  filters::NoiseModel model = filters::NoiseModel::rq;
  TuneOutcome outcome;  // baseline_mean and tuned_mean are the row's errors
};

struct DemoOutcome {
  std::vector<DemoRow> rows;      // track by track, rq, alpha, gyro for each
  long evaluations_per_tune = 0;  // particles × (iterations + 1)
  double seconds = 0.0;           // optimisation time summed over the tunes
};

// Where the command hears of the demo's progress (each may be empty).
struct DemoCallbacks {
  // Once the tracks are read and prepared, before the first tune. Returns the
  // flag that stops the demo when raised (null: never stopped).
  std::function<const std::atomic<bool>*()> started;
  // Before each tune: its label ("demo track1 rq"), the tunes done and in all.
  std::function<void(const std::string& label, long done, long total)> tune_started;
  // After each tune, in table order: its row, the tunes done (it included) and in all.
  std::function<void(const DemoRow& row, long done, long total)> row;
  // After the last tune, before the JSON is written.
  std::function<void(const DemoOutcome&)> finished;
};

// Runs the 15 tunes one after another (each on all OpenMP threads).
// Throws core::Failure when a track file is missing ("PATH: reference
// track not found (use --data DIR)") or unreadable, Failure("interrupted",
// 130) when the stop flag was raised during a tune (that tune has no row),
// and Failure when the JSON cannot be written; std::invalid_argument when a
// track cannot be replayed (prepare_track) and std::runtime_error when the
// solver fails.
DemoOutcome run_demo(const DemoRequest& request, const DemoCallbacks& callbacks);

}  // namespace odotune::jobs

// Shared pieces of the commands' output: metrics as JSON and text, track
// loading with one-line errors, the OpenMP thread option, Ctrl-C.
#pragma once

#include <atomic>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "cli/tune_job.h"
#include "objectives/metrics.h"
#include "tracks/track.h"

namespace odotune::cli {

nlohmann::json metrics_json(const ErrorMetrics& m);
// The --json document of `tune` (see README for the keys).
nlohmann::json tune_json(const TuneOutcome& o);

// "  47.88 →  29.31 mm  (+38.8 %)"
std::string metric_change(double baseline_m, double tuned_m);

// Reads track files; a bad file becomes one Failure line (file:line: reason).
std::vector<Track> load_tracks(const std::vector<std::string>& paths);

// Adds --threads to a command; apply_threads() sets OpenMP's thread count
// (0 = OpenMP's default, all cores).
void add_threads_option(CLI::App* sub, int* threads);
void apply_threads(int threads);

// A flag raised by SIGINT/SIGTERM while the guard lives (first Ctrl-C stops
// cleanly, a second one kills as usual).
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  const std::atomic<bool>* flag() const;
  bool raised() const;
};

}  // namespace odotune::cli

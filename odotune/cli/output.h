// Shared pieces of the commands' output: metric changes and tune results as
// text, the OpenMP thread option, Ctrl-C. (The JSON of a tune is
// odotune/jobs/tune_json.h; loading tracks with one-line errors, odotune/tracks/track_io.h.)
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include <odotune/jobs/tune_job.h>
#include <odotune/objectives/fitness_mode.h>
#include <odotune/objectives/metrics.h>
#include <odotune/tracks/track.h>

namespace odotune::cli {

// Prints each line and a newline on stdout (the text a job returns).
void print_lines(const std::vector<std::string>& lines);

// "  47.88 →  29.31 mm  (+38.8 %)"
std::string metric_change(double baseline_m, double tuned_m);

// The lines `tune` prints under its heading for a noise model (EKF or UKF):
// RMSE/MAE/MAXE change, per track when several, the tuned parameters and the
// solver's evaluations, time, termination and diverged evaluations.
void print_tune_result(const objectives::ErrorMetrics& baseline_mean,
                       const objectives::ErrorMetrics& tuned_mean, const std::vector<jobs::TrackScore>& tracks,
                       const std::vector<std::string>& param_names, const std::vector<double>& params,
                       const tuner::Summary& summary, long diverged);

// Adds --mode, which takes a fitness mode's number or key ("7",
// "rmse+mae+maxe"); with `ground_truth_only` modes 8 and 9 are refused at the
// flag. `set` receives the parsed mode.
CLI::Option* add_fitness_mode_option(CLI::App* sub, std::function<void(objectives::FitnessMode)> set,
                                     const std::string& help, bool ground_truth_only = false);

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

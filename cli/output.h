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

// The pieces every tune's --json shares (tune, the calibrator and UKF tunes):
// {"rmse", "mae", "maxe"} improvement in %, the per-track baseline/tuned
// metrics, and the solver's convergence log.
nlohmann::json improvement_json(const ErrorMetrics& baseline, const ErrorMetrics& tuned);
nlohmann::json track_scores_json(const std::vector<TrackScore>& tracks);
nlohmann::json convergence_json(const tuner::Summary& summary);
// The tuned and default values by parameter name, into j: "params",
// "param_units", "default_params" (each an object keyed by name) and
// "default_kept" (the calibrator and UKF tunes, which start from defaults).
void put_tuned_params_json(nlohmann::json& j, const std::vector<std::string>& names,
                           const std::vector<std::string>& units, const std::vector<double>& tuned,
                           const std::vector<double>& defaults, bool default_kept);

// The lines `tune` prints under its heading for a noise model (EKF or UKF):
// RMSE/MAE/MAXE change, per track when several, the tuned parameters and the
// solver's evaluations, time, termination and diverged evaluations.
void print_tune_result(const ErrorMetrics& baseline_mean, const ErrorMetrics& tuned_mean,
                       const std::vector<TrackScore>& tracks,
                       const std::vector<std::string>& param_names,
                       const std::vector<double>& params, const tuner::Summary& summary,
                       long diverged);

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

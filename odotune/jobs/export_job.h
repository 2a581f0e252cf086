// `odotune export` without its flags (odotune/cli/cmd_export.cpp reads those and
// prints): one run of a results store as a configuration file, either
// odotune's own (what `eval --config` reads) or a ROS 2 parameter file for
// robot_localization's ekf_node (odotune/results/ros_export.h; alpha/gyro mapped by
// odotune/objectives/process_noise_rate.h).
//
// Selection: --select key=value filters (model, track, mode, seed, heldout)
// must leave runs of exactly one model; of those the run with the lowest tuned
// RMSE on its scored track is exported (ties: the first stored). An rl-ekf
// run (robot_localization's EKF) is scored on data its tune never saw, so its
// runs must be of one fitness and are compared by their tuning fitness; it
// exports as the robot's own parameter file (odotune/jobs/rl_job.h, write_rl_run). A run of a
// calibrator model (pf-calib, adaptive-pf-calib) is refused with one line:
// it holds PF settings, not EKF noise (tune --config-out writes those). A run
// of the fusion UKF (ukf) exports as odotune's own format only (an
// odotune-ukf-config/1 file, odotune/formats/ukf_config_yaml.h); robot_localization has
// no mapping for it (its filters estimate the pose, not a (V, W) fusion of
// this form), which is refused with one line.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/results/run_record.h>

namespace odotune::jobs {

// What a --select filter compares: a stored run's model, track (e.g.
// "all-but-track1"), fitness mode, seed, or held-out track ("none").
enum class RunKey { model, track, mode, seed, heldout };
inline constexpr std::array<RunKey, 5> kAllRunKeys = {RunKey::model, RunKey::track, RunKey::mode, RunKey::seed,
                                                      RunKey::heldout};
std::string_view to_string(RunKey k);  // "model", "track", "mode", "seed", "heldout"
bool parse_run_key(std::string_view text, RunKey* out);

// One --select filter: a run's `key` must equal `value`, a stored value as
// the user writes it (the store's names and numbers are data).
struct RunFilter {
  RunKey key = RunKey::model;
  std::string value;  // normalised (integers without leading zeros or '+')
  std::string text() const { return std::string(to_string(key)) + "=" + value; }
};

// Parses key=value items (each --select item, commas already split; the cli
// calls it on the flag's items). Throws core::Failure (one line naming the
// item) for a malformed item, an unknown key, a mode or seed that is not a
// non-negative integer, or one key given twice with different values.
std::vector<RunFilter> parse_run_filters(const std::vector<std::string>& items);

struct RunSelection {
  const results::RunRecord* run = nullptr;  // points into the runs selected from
  std::size_t matching = 0;                 // runs that passed the filters
};

// Applies the filters in order (so a failure names the filter that left
// nothing and the values that key has), checks that the runs left are of one
// model and picks the lowest tuned RMSE (ties: the first). Throws
// core::Failure for no runs (naming `store`), a filter that leaves none, or
// runs of several models.
RunSelection select_best_run(const std::vector<results::RunRecord>& runs, const std::vector<RunFilter>& filters,
                             const std::string& store);

// What export writes: odotune's own configuration file (what `eval --config`
// reads), or a parameter file for robot_localization.
enum class ExportFormat { odotune, robot_localization };
inline constexpr std::array<ExportFormat, 2> kAllExportFormats = {ExportFormat::odotune,
                                                                  ExportFormat::robot_localization};
std::string_view to_string(ExportFormat f);  // "odotune", "robot_localization"
bool parse_export_format(std::string_view text, ExportFormat* out);

struct ExportRequest {
  std::string store;              // results store written by `odotune grid`
  std::vector<RunFilter> select;  // --select, parsed (parse_run_filters)
  ExportFormat format = ExportFormat::odotune;
  std::string out;                            // the file to write (atomically)
  std::vector<std::string> track_files;       // take precedence over the experiment's tracks
  std::string node_name = "ekf_filter_node";  // robot_localization: the top-level key
  bool ros1 = false;                          // rl-ekf runs: the ROS 1 form (default ROS 2)
};

struct ExportOutcome {
  std::string run_key;       // results::run_key of the exported run
  std::string scores;        // "tuned RMSE … mm vs baseline … mm on TRACK"
  std::size_t matching = 0;  // runs the selection matched (the exported one is their best)
};

// Opens the store read-only, selects the run and writes `out`: an
// odotune-ekf-config/1 file (or odotune-ukf-config/1 for a ukf run) for
// ExportFormat::odotune, a robot_localization parameter file otherwise (which needs the
// run's tuning tracks, from the experiment or `track_files`, for the
// odometry rate and, for alpha/gyro, the time-averaged process noise).
// Throws core::Failure (one line) for a bad selection or store, a
// calibrator run, a ukf run to robot_localization, a missing track or a run
// that cannot be mapped; nothing is written then.
ExportOutcome run_export(const ExportRequest& request);

}  // namespace odotune::jobs

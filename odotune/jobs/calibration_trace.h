// The estimates of a calibration run over time as one table: the run's
// trace (odotune/calibration/calibration_run.h) with, per row, the time elapsed since
// the calibration began and the truth where the track knows it. This is what
// `calibrate --csv` writes and what its figure (odotune/jobs/calibration_figure_data.h)
// and the study's figures draw.
//
// Elapsed time puts the tracks end to end: track k's rows are at
// offset_k + (t − t_k,first), where t_k,first is the track's first odometry
// row and offset_k the summed durations (last − first odometry row) of the
// tracks before it. With one track elapsed_s = t_s − t_first.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_run.h>

namespace odotune::jobs {

struct CalibrationTraceTable {
  std::vector<std::string> track_names;       // per input, in order
  std::vector<double> track_start_elapsed_s;  // offset_k of each track [s]
  std::vector<double> track_end_elapsed_s;    // offset_k + its duration [s]
  // Truth change times (radius steps) on the elapsed axis, with the index of
  // the track they belong to.
  std::vector<double> change_elapsed_s;
  std::vector<int> change_track;
  // The truth of the tracks that know it, as constant pieces on the elapsed
  // axis (from the track's first odometry row to its last, split at the
  // changes), in time order.
  struct TruthPiece {
    int track = 0;
    double from_elapsed_s = 0.0, to_elapsed_s = 0.0;
    filters::OdometryParams params;
  };
  std::vector<TruthPiece> truth_pieces;

  // One row per iteration of the run (all columns equally long).
  std::vector<double> t_s;        // on the track's own clock [s]
  std::vector<double> elapsed_s;  // [s]
  std::vector<int> track;         // input index
  std::vector<filters::CalibEstimate> estimate;
  std::vector<std::optional<filters::OdometryParams>> truth;  // nullopt: this track has no truth
  bool any_truth = false;                                     // some row has a truth

  // Methods with fixed parameters (batch, none; their trace has one row per
  // track): per track, the constants it used. Empty for online methods.
  std::vector<filters::OdometryParams> fixed_params;
};

// Throws std::invalid_argument when the trace refers to a track index
// outside `inputs` or its columns differ in length.
CalibrationTraceTable build_trace_table(const calibration::CalibrationResult& result,
                                        const std::vector<const calibration::CalibrationInput*>& inputs);

// The table as CSV text, header first:
//   t_s, elapsed_s, track, r_right_m, r_left_m, wheel_base_m,
//   sd_r_right_m, sd_r_left_m, sd_wheel_base_m, particles, n_eff
// and, when any row has a truth, true_r_right_m, true_r_left_m,
// true_wheel_base_m (empty cells for tracks without truth). Numbers at full
// precision; a track name with a comma or quote is quoted (RFC 4180).
std::string trace_csv(const CalibrationTraceTable& table);

}  // namespace odotune::jobs

// From a calibration run's table (odotune/jobs/calibration_trace.h) to the plain data
// of the estimates-over-time figure (odotune/results/calibration_figures.h): the
// figure of `calibrate --figure`, and the series the study command combines
// into "radii over time, several methods or runs" figures.
#pragma once

#include <string>
#include <vector>

#include <odotune/jobs/calibration_trace.h>
#include <odotune/results/calibration_figures.h>

namespace odotune::jobs {

// The lines of one run on the elapsed-time axis: R_R and R_L in `radii`
// ("R_R LABEL", "R_L LABEL"; "R_R", "R_L" when label is empty), D in
// `wheel_base`. R_R takes palette colour first_colour, R_L first_colour + 1,
// D first_colour + 2. with_sd adds the ±sd bands. Long traces are thinned
// to at most max_points rows (every k-th row, the last one kept). A run with
// fixed parameters (batch, none) gives a flat line over each track.
struct RunSeries {
  std::vector<results::EstimateSeries> radii, wheel_base;
};
RunSeries estimate_series(const CalibrationTraceTable& table, const std::string& label, int first_colour,
                          bool with_sd, std::size_t max_points = 4000);

// The truth as dashed lines ("R_R true", "R_L true", "D true", in colours
// first_colour, +1, +2): the table's truth pieces, a step at each change, a
// gap between tracks; empty when no track knows its truth.
RunSeries truth_series(const CalibrationTraceTable& table, int first_colour);

// Markers: track starts (after the first, labelled with the track's name)
// and truth changes ("radius step").
std::vector<results::CalibrationFigureData::Marker> run_markers(const CalibrationTraceTable& table);

// The figure of `calibrate --figure`: the run's estimates with ±sd bands,
// the truth dashed in the same colours, the markers.
results::CalibrationFigureData calibration_figure_data(const CalibrationTraceTable& table,
                                                       const std::string& title);

}  // namespace odotune::jobs

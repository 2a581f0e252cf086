// The figure of odometry-parameter estimates over time (`odotune calibrate
// --figure`, and the study's "radii over time" figures, the analogues of
// Figures 6 and 8 of Fariña, Toledo & Acosta, RA-L 2026): one panel for the
// wheel radii and, below it, one for the wheel base, sharing the time axis.
//
// Plain data only (the results layer does not see the calibrators): each
// panel holds named series of (t, value) with an optional ±sd band; a truth
// series is drawn dashed. Conventions of odotune/results/figures.h: STEM.png
// (pngcairo) + STEM.svg, both or neither; the stem's directory must exist;
// texts verbatim (`noenhanced`); axes labelled with units.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace odotune::results {

// One line of a panel. t_s and value_m have the same length; a NaN in
// either breaks the line. sd_m is empty (no band) or as long as t_s: the
// band value ± sd is shaded in the series' colour (rows with a NaN sd are
// left out of the band).
struct EstimateSeries {
  std::string name;             // legend entry, e.g. "R_R adaptive-pf" or "R_R true"
  std::vector<double> t_s;      // [s]
  std::vector<double> value_m;  // [m]
  std::vector<double> sd_m;     // [m], optional
  bool truth = false;           // drawn dashed (and black unless colour is set)
  // Index into the figure's colour-blind-safe palette (Okabe & Ito 2008;
  // taken modulo its size), so that an estimate and its truth can share a
  // colour. nullopt: estimates take the next unused colour, truths black.
  std::optional<int> colour;
};

struct CalibrationFigureData {
  std::string title;                       // e.g. "track_a: adaptive-pf calibration"
  std::vector<EstimateSeries> radii;       // upper panel, "wheel radius [m]"; at least one series
  std::vector<EstimateSeries> wheel_base;  // lower panel, "wheel base [m]"; empty = no lower panel
  // Thin vertical lines in both panels with a short label at the top of the
  // upper panel (track boundaries, radius steps). Times [s] on the series'
  // axis; labels may be empty.
  struct Marker {
    double t_s = 0.0;
    std::string label;
  };
  std::vector<Marker> markers;
  std::string time_label = "time [s]";  // x axis label (with its unit)
};

// Draws the figure to STEM.png and STEM.svg. Throws std::invalid_argument
// (before drawing) when `radii` is empty, a series' lengths differ (the
// message names the series and both lengths), a panel has no finite point
// or a marker time is not finite; std::runtime_error when gnuplot is missing
// or fails or the stem's directory does not exist.
void calibration_estimates_figure(const std::filesystem::path& stem, const CalibrationFigureData& data);

}  // namespace odotune::results

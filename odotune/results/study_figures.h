// Figures of the calibration studies (`odotune study resampling|calibration`,
// analogues of Figures 3–6 of Fariña, Toledo & Acosta, RA-L 2026) that the
// single-run estimate figure (odotune/results/calibration_figures.h) does not cover:
// grouped bars with error bars, and stacked time-series panels with many
// runs (one colour per run, its truth dashed in the same colour).
//
// Plain data only. Conventions of odotune/results/figures.h: STEM.png (pngcairo) +
// STEM.svg, both or neither; the stem's directory must exist; texts verbatim
// (`noenhanced`); axes labelled with units by the caller's labels. Throws
// std::invalid_argument on malformed input (before drawing) and
// std::runtime_error when gnuplot is missing or fails.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace odotune::results {

// One panel of grouped bars: mean[g][s] ± sd[g][s] for group g (x axis) and
// series s (one colour each, with a legend). NaN means draw no bar; a NaN
// or zero sd draws no error bar.
struct BarPanel {
  std::string ylabel;                     // with its unit, e.g. "normalised error [-]"
  std::vector<std::vector<double>> mean;  // [group][series]
  std::vector<std::vector<double>> sd;    // [group][series], same shape
};

// Panels stacked top to bottom sharing the group axis. Throws
// std::invalid_argument when groups or series are empty, a panel's shape is
// not groups × series, or no bar value is finite.
void grouped_bars(const std::filesystem::path& stem, const std::string& title,
                  const std::vector<std::string>& groups, const std::vector<std::string>& series,
                  const std::vector<BarPanel>& panels);

// One line of a time panel; NaN breaks the line.
struct PanelLine {
  std::string name;         // legend entry; "" = none
  std::vector<double> t_s;  // [s]
  std::vector<double> y;    // in the panel's unit
  int colour = 0;           // index into a 10-colour palette (modulo)
  bool dashed = false;      // truth lines: dashed, drawn as steps
  bool thin = false;        // many-run lines: thinner
};

struct TimePanel {
  std::string ylabel;  // with its unit
  std::vector<PanelLine> lines;
};

// A vertical marker line through every panel, labelled in the top one.
struct TimeMarker {
  double t_s = 0.0;
  std::string label;
};

// The gnuplot `set label` commands that label the markers (drawn in the top
// panel), numbered from 1; markers without a label are skipped.
std::string time_marker_labels(const std::vector<TimeMarker>& markers);

// Panels stacked top to bottom on a shared time axis ("time [s]"). Throws
// std::invalid_argument when there is no panel, a line's t_s and y differ in
// length (naming the panel and line), a panel has no finite point or a
// marker is not finite.
void time_panels(const std::filesystem::path& stem, const std::string& title,
                 const std::vector<TimePanel>& panels, const std::vector<TimeMarker>& markers);

}  // namespace odotune::results

// Figures of the learned-odometry study (`odotune study learned`), the
// analogues of Figs. 6, 7, 8 and 10 of Fariña, Acosta, Toledo & Acosta,
// "Improving Odometric Model Performance Based on LSTM Networks", Sensors
// 2023, 23, 961 (../shared/papers/002_*.txt):
//   * time panels with shaded intervals (slip episodes) and vertical markers
//     (radius change, retrain instants), each panel linear or log y — the
//     detector's variance rising during slip (Fig. 6) and the velocity error
//     with and without retraining (Fig. 7);
//   * XY path panels side by side, equal axis scales (Figs. 8, 10).
//
// Plain data only (the results layer does not see the filters). Conventions of
// odotune/results/figures.h: STEM.png (pngcairo) + STEM.svg, both or neither; the
// stem's directory must exist; texts verbatim (`noenhanced`); axes labelled
// with units by the caller's labels. Throws std::invalid_argument on malformed
// input (before drawing) and std::runtime_error when gnuplot is missing or
// fails.
#pragma once

#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <odotune/results/study_figures.h>

namespace odotune::results {

// A shaded time interval drawn behind every panel [s]; t1_s > t0_s.
struct TimeShade {
  double t0_s = 0.0, t1_s = 0.0;
};

struct ShadedPanel {
  std::string ylabel;  // with its unit
  bool log_y = false;  // log scale: values ≤ 0 break the line like NaN
  // Lower end of the y axis (NaN: automatic); points below it are clipped by
  // the axis, not dropped (e.g. squared errors of 1e-12 on a variance panel).
  double y_min = std::numeric_limits<double>::quiet_NaN();
  std::vector<PanelLine> lines;  // PanelLine of study_figures.h (dashed: steps)
};

// Panels stacked top to bottom on a shared time axis ("time [s]"); `shades`
// grey behind every panel, titled `shade_label` in the key when non-empty;
// `markers` as vertical dotted lines labelled in the top panel. Throws
// std::invalid_argument when there is no panel, a line's lengths differ
// (naming panel and line), a panel has no plottable point, a shade is not
// finite or has t1_s ≤ t0_s, or a marker is not finite.
void shaded_time_panels(const std::filesystem::path& stem, const std::string& title,
                        const std::vector<ShadedPanel>& panels, const std::vector<TimeShade>& shades,
                        const std::string& shade_label, const std::vector<TimeMarker>& markers);

// One path of an XY panel [m]; NaN breaks the line.
struct PathLine {
  std::string name;  // legend entry
  std::vector<double> x_m, y_m;
  int colour = 0;  // palette index (study_figures.h's 10 colours); -1 = black
  bool dashed = false;
};

struct PathPanel {
  std::string title;  // the panel's own title
  std::vector<PathLine> lines;
};

// Panels side by side, each with equal x and y scales ("x [m]", "y [m]"),
// a start marker at the first finite point of the first line. Throws
// std::invalid_argument when there is no panel, a line's x and y differ in
// length, or a panel has no finite point.
void path_panels(const std::filesystem::path& stem, const std::string& title,
                 const std::vector<PathPanel>& panels);

}  // namespace odotune::results

// The figures of `odotune diagnose TRACK --report DIR` (sim-to-real
// diagnosis), rendered with gnuplot like the study's figures (results/
// figures.h): each figure is STEM.png (pngcairo) + STEM.svg, both or neither,
// texts verbatim (`noenhanced`), axes labelled with units, titles naming the
// track. Takes plain data: the results layer does not see diagnose/.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <odotune/results/figures.h>

namespace odotune::results {

struct TimeSpan {
  double t0_s, t1_s;  // t0_s <= t1_s, track time [s]
};

struct MapBox {
  double x0_m, x1_m, y0_m, y1_m;  // x0_m <= x1_m, y0_m <= y1_m, map frame [m]
};

// Everything the diagnosis figures show. Rows of one block share their
// length (checked; see diagnosis_figures()).
struct DiagnosisFigureData {
  std::string track;    // for titles
  std::string finding;  // e.g. "lateral_skid k = 0.021 ± 0.002" ("" = no finding)

  // 1. Residual vs time: one value per reference sample, from a window
  //    replay re-anchored at every window start. NaN breaks the line.
  std::vector<double> t_s;
  std::vector<double> before_pos_err_m;  // |predicted - reference| position, nominal model
  std::vector<double> after_pos_err_m;   // the same with the finding; empty = no finding
  std::vector<TimeSpan> segments;        // located segments, shaded
  std::vector<double> window_starts_s;   // thin vertical lines (re-anchoring)

  // 2. Residual vs the responsible condition, before and after (skipped when
  //    condition_value is empty). Rows with a NaN are left out.
  std::string condition_label;  // e.g. "|v*w| [m/s^2]"
  std::string residual_label;   // e.g. "lateral error growth [m/s]"
  std::vector<double> condition_value;
  std::vector<double> before_residual;
  std::vector<double> after_residual;  // empty = no finding

  // 3. Map with the located regions.
  std::vector<double> ref_x_m, ref_y_m;  // reference path
  std::vector<std::uint8_t> flagged;     // per reference row, 1 = residual exceeds noise; may be empty
  std::vector<MapBox> regions;           // outlined, labelled "region 1", "region 2", …

  // 4. Trajectory overlay (reference, nominal replay, corrected replay, …);
  //    the first path is drawn in black. At least one path.
  std::vector<TrajectoryPath> overlay;
};

// Writes DIR/residual_time.{png,svg}, residual_condition.{png,svg} (skipped
// when condition_value is empty), map.{png,svg} and overlay.{png,svg};
// returns the stems written (DIR/residual_time, …) in that order. DIR must
// exist. All input is checked before the first figure is drawn: throws
// std::invalid_argument on mismatched lengths (the message names the field
// and both lengths), on an empty t_s / ref path / overlay, on a series
// without a finite value, or on a malformed span or box; std::runtime_error
// when gnuplot is missing or fails (figures drawn before stay).
std::vector<std::filesystem::path> diagnosis_figures(const std::filesystem::path& dir,
                                                     const DiagnosisFigureData& data);

// Median trend of y over x in `bins` quantile bins: the rows where both are
// finite, sorted by x (stable), split into `bins` consecutive groups of
// (almost) equal count (the first n % bins groups get one more row); per
// group the median x and the median y. Fewer groups when there are fewer
// rows than bins; empty when no row is finite. Throws std::invalid_argument
// when x and y differ in length or bins < 1.
struct BinnedMedian {
  std::vector<double> x, y;
};
BinnedMedian binned_median(const std::vector<double>& x, const std::vector<double>& y, int bins);

}  // namespace odotune::results

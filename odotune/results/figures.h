// The report's figures, rendered with gnuplot (see odotune/results/gnuplot.h).
//
// Every function takes plain data and an output path stem and writes
// STEM.png (pngcairo) and STEM.svg, both or neither; the stem's directory
// must exist. Figures are titled, axes are labelled with units, texts are
// shown verbatim (gnuplot `noenhanced`, so `_` or `^` are not markup).
// Throws std::invalid_argument on malformed input and std::runtime_error
// when gnuplot is missing or fails or the output directory does not exist.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <odotune/objectives/fitness_mode.h>
#include <odotune/results/run_record.h>

namespace odotune::results {

// Row labels of the heatmap: "1 RMSE", "2 MAE", …, "7 RMSE+MAE+MAXE".
std::string heatmap_mode_label(objectives::FitnessMode mode);

// Improvement % over the baseline per fitness mode × track (the study's
// Figure 3): rows = modes 1..7 (top to bottom), columns = `columns`, each
// cell coloured on a diverging palette centred at 0 (symmetric range
// ±max|value|) with its value printed to one decimal. NaN cells are drawn
// grey and labelled "n/a". `values` must be 7 rows of columns.size() values.
void heatmap(const std::filesystem::path& stem, const std::string& title,
             const std::vector<std::string>& columns, const std::vector<std::vector<double>>& values);

struct BoxplotOptions {
  std::string group_label = "model";  // the x axis label: what the groups are
  bool points = false;                // every value as a point over its box
};

// Improvement % per model (groups on the x axis) for each metric (one box
// colour per metric, with a legend) — the study's Figure 4. Input:
// model → metric ("RMSE", "MAE", "MAXE"; other names are appended in
// alphabetical order) → values in %. NaN values are ignored; empty
// vectors draw no box. A box of 4 or more values is a boxplot (quartiles,
// whiskers to 1.5 IQR, the values beyond as points); one of 1 to 3 values
// is drawn as a box from their minimum to their maximum (a line for one
// value) with a thick line at the median and every value as a point, so
// every value is drawn and inside the y range. With options.points every
// value of every box is a point, in the order given, spread across the box.
// Throws std::invalid_argument when there is no value.
void boxplots(const std::filesystem::path& stem, const std::string& title,
              const std::map<std::string, std::map<std::string, std::vector<double>>>& data,
              const BoxplotOptions& options = {});

// Statistics over several runs' convergence curves resampled onto the union
// of their evaluation counts. A run is step-wise constant (its value at e is
// that of its last point with evaluations <= e, points taken in order of
// evaluations) and undefined before its first point; it holds its last
// value after its last point.
struct ConvergenceBand {
  std::vector<long> evaluations;               // strictly increasing grid
  std::vector<double> median_m, min_m, max_m;  // over the runs defined there
  std::vector<int> runs;                       // how many runs were defined
};
ConvergenceBand resample_convergence(const std::vector<std::vector<ConvergencePoint>>& runs);

// Best fitness vs evaluations (step-wise), one colour per series: the median
// over the series' runs as a line and the min–max range as a shaded band
// (the legend says so). Input: series name → runs. Series without points
// are skipped; throws std::invalid_argument when no series has a point.
void convergence(const std::filesystem::path& stem, const std::string& title,
                 const std::map<std::string, std::vector<std::vector<ConvergencePoint>>>& series);

// One named x–y path in metres. NaN entries break the line.
struct TrajectoryPath {
  std::string name;
  std::vector<double> xs_m, ys_m;
};

// Overlay of paths with equal axis scale and a legend (the study's
// Figure 5). The plot area is fitted to the paths (their bounding box with a
// margin of 3 % of its larger side, at most 820 × 680 px, widened about its
// centre to at least 220 px a side and to the title's width), the canvas
// sized around it with the legend on the right. The first path is drawn in black (by convention the ground
// truth), the others in distinct colours. Throws std::invalid_argument when
// `paths` is empty, a path's xs/ys differ in length or nothing is finite.
void trajectories(const std::filesystem::path& stem, const std::string& title,
                  const std::vector<TrajectoryPath>& paths);

}  // namespace odotune::results

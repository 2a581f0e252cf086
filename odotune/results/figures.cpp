#include <odotune/results/figures.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include <odotune/core/robust_stats.h>
#include <odotune/results/gnuplot.h>

namespace odotune::results {
namespace fs = std::filesystem;

namespace {

// Colour-blind-safe series colours (Okabe & Ito 2008), yellow left out.
const char* const kSeriesColours[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                      "#E69F00", "#56B4E9", "#000000"};
constexpr std::size_t kNumSeriesColours = sizeof(kSeriesColours) / sizeof(kSeriesColours[0]);

const char* series_colour(std::size_t i) { return kSeriesColours[i % kNumSeriesColours]; }

std::string num_figure(double v) { return gnuplot_number(v); }

// One decimal, without a "-0.0".
std::string one_decimal(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  std::string s = buf;
  if (s == "-0.0") s = "0.0";
  return s;
}

std::string q_figure(const std::string& s) { return gnuplot_quote(s); }

// `set xtics (...)`/`set ytics (...)` list for categorical positions 0..n-1
// (or `first`, `first+1`, …).
std::string category_tics(const std::vector<std::string>& names, int first) {
  std::string s = "(";
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) s += ", ";
    s += q_figure(names[i]) + " " + std::to_string(first + static_cast<int>(i));
  }
  return s + ")";
}

}  // namespace

// ---------------------------------------------------------------- heatmap

std::string heatmap_mode_label(objectives::FitnessMode mode) {
  return std::to_string(objectives::number(mode)) + " " + objectives::fitness_mode_name(mode);
}

void heatmap(const fs::path& stem, const std::string& title, const std::vector<std::string>& columns,
             const std::vector<std::vector<double>>& values) {
  constexpr auto kModes = static_cast<int>(objectives::kGroundTruthModes.size());
  if (columns.empty()) throw std::invalid_argument("heatmap: no columns (tracks)");
  if (values.size() != kModes) {
    throw std::invalid_argument("heatmap: expected 7 rows (fitness modes 1..7), got " +
                                std::to_string(values.size()));
  }
  double max_abs = 0.0;
  for (std::size_t r = 0; r < values.size(); ++r) {
    if (values[r].size() != columns.size()) {
      throw std::invalid_argument("heatmap: row " + std::to_string(r + 1) + " has " +
                                  std::to_string(values[r].size()) + " values, expected " +
                                  std::to_string(columns.size()) + " (one per column)");
    }
    for (double v : values[r]) {
      if (std::isfinite(v)) max_abs = std::max(max_abs, std::abs(v));
    }
  }
  // Symmetric colour range, at least ±1 %, rounded up to a whole percent.
  const double range = std::max(1.0, std::ceil(max_abs));

  // cells: x y value; labels: x y "text" (dark or light text by background).
  std::string cells, missing, dark_labels, light_labels;
  for (int r = 0; r < kModes; ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const double v = values[r][c];
      const std::string xy = std::to_string(c) + " " + std::to_string(r);
      if (!std::isfinite(v)) {
        missing += xy + " \"n/a\"\n";
        continue;
      }
      cells += xy + " " + num_figure(v) + "\n";
      (std::abs(v) > 0.6 * range ? light_labels : dark_labels) += xy + " \"" + one_decimal(v) + "\"\n";
    }
  }

  std::vector<std::string> mode_names;
  mode_names.reserve(objectives::kGroundTruthModes.size());
  for (objectives::FitnessMode m : objectives::kGroundTruthModes) mode_names.push_back(heatmap_mode_label(m));
  std::size_t longest = 0;
  for (const auto& c : columns) longest = std::max(longest, c.size());
  const int ncols = static_cast<int>(columns.size());

  std::string body;
  body += "set title " + q_figure(title) + " font ',13'\n";
  body += "set xlabel 'track'\nset ylabel 'fitness mode'\n";
  body += "set cblabel 'improvement [%]'\n";
  body += "set xrange [-0.5:" + num_figure(ncols - 0.5) + "]\nset yrange [6.5:-0.5]\n";
  body += "set xtics " + category_tics(columns, 0) + " scale 0" + (longest > 8 ? " rotate by 30 right" : "") +
          "\n";
  body += "set ytics " + category_tics(mode_names, 0) + " scale 0\n";
  body += "set palette defined (-1 '#b2182b', -0.5 '#ef8a62', 0 '#f7f7f7', 0.5 '#67a9cf', "
          "1 '#2166ac')\n";
  body += "set cbrange [" + num_figure(-range) + ":" + num_figure(range) + "]\nset colorbox\n";
  body += "unset key\nset border 0\nset style fill solid 1.0 noborder\n";
  std::string plot = "plot ";
  auto add = [&plot](const std::string& clause) {
    if (plot != "plot ") plot += ", \\\n     ";
    plot += clause;
  };
  // A palette clause is always present so the colour box is drawn even when
  // every cell is missing.
  add(cells.empty() ? "NaN with points lc palette notitle"
                    : "'cells.dat' using 1:2:(0.5):(0.5):3 with boxxyerror fc palette notitle");
  if (!missing.empty()) {
    add("'missing.dat' using 1:2:(0.5):(0.5) with boxxyerror fc rgb '#c8c8c8' notitle");
    add("'missing.dat' using 1:2:3 with labels tc rgb '#505050' notitle");
  }
  if (!dark_labels.empty()) add("'dark.dat' using 1:2:3 with labels tc rgb 'black' notitle");
  if (!light_labels.empty()) add("'light.dat' using 1:2:3 with labels tc rgb 'white' notitle");
  body += plot + "\n";

  const int width = std::max(700, 260 + 95 * ncols);
  const int height = 560 + (longest > 8 ? static_cast<int>(std::min<std::size_t>(longest, 40)) * 5 : 0);
  render_png_svg(
      stem,
      {{"cells.dat", cells}, {"missing.dat", missing}, {"dark.dat", dark_labels}, {"light.dat", light_labels}},
      body, width, height);
}

// ---------------------------------------------------------------- boxplots

namespace {

// Fewer values than this draw no gnuplot boxplot: gnuplot 5.4's `with
// boxplot` under `nooutliers` draws nothing for 1–3 points and leaves them
// out of the autoscaled range (a figure of one run per box came out empty,
// on an axis of −1…1).
constexpr std::size_t kMinBoxplotValues = 4;

std::vector<double> finite_values(const std::vector<double>& values) {
  std::vector<double> v;
  for (double d : values)
    if (std::isfinite(d)) v.push_back(d);
  return v;
}

// Outliers of a box as "x y" lines, one per distinct value (to 1e-6),
// beyond 1.5 × IQR from the quartiles (linear interpolation between order
// statistics, as gnuplot's boxplot); empty when there is none.
std::string boxplot_outliers(std::vector<double> v, double x) {
  if (v.size() < kMinBoxplotValues) return "";
  std::sort(v.begin(), v.end());
  const auto quantile = [&v](double p) {
    const double pos = p * static_cast<double>(v.size() - 1);
    const auto i = static_cast<std::size_t>(pos);
    const double f = pos - static_cast<double>(i);
    return i + 1 < v.size() ? v[i] + f * (v[i + 1] - v[i]) : v[i];
  };
  const double q1 = quantile(0.25), q3 = quantile(0.75), iqr = q3 - q1;
  std::string out;
  double last = std::numeric_limits<double>::quiet_NaN();
  for (double d : v) {
    if (d >= q1 - 1.5 * iqr && d <= q3 + 1.5 * iqr) continue;
    if (std::abs(d - last) <= 1e-6) continue;
    out += num_figure(x) + " " + num_figure(d) + "\n";
    last = d;
  }
  return out;
}

// A box of fewer than kMinBoxplotValues values, as one line
// "x y_median x_lo x_hi y_min y_max": drawn as a box from the minimum to the
// maximum (a line for one value) and a line at the median.
std::string small_box(std::vector<double> v, double x, double width) {
  std::sort(v.begin(), v.end());
  const double median = core::sorted_median(v);
  return num_figure(x) + " " + num_figure(median) + " " + num_figure(x - width / 2) + " " +
         num_figure(x + width / 2) + " " + num_figure(v.front()) + " " + num_figure(v.back()) + "\n";
}

// Every value as "x y", in the given order, spread evenly across 60 % of the
// box's width so that equal values stay apart.
std::string value_points(const std::vector<double>& v, double x, double width) {
  std::string out;
  const auto n = static_cast<double>(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double dx = v.size() == 1 ? 0.0 : 0.6 * width * ((static_cast<double>(i) + 0.5) / n - 0.5);
    out += num_figure(x + dx) + " " + num_figure(v[i]) + "\n";
  }
  return out;
}

}  // namespace

void boxplots(const fs::path& stem, const std::string& title,
              const std::map<std::string, std::map<std::string, std::vector<double>>>& data,
              const BoxplotOptions& options) {
  // Metric order: RMSE, MAE, MAXE, then any other in alphabetical order.
  std::vector<std::string> metrics = {"RMSE", "MAE", "MAXE"};
  for (const auto& [model, by_metric] : data) {
    for (const auto& [metric, vals] : by_metric) {
      if (std::find(metrics.begin(), metrics.end(), metric) == metrics.end()) {
        metrics.push_back(metric);
      }
    }
  }
  std::sort(metrics.begin() + 3, metrics.end());
  const char* const metric_colours[] = {"#0072B2", "#E69F00", "#009E73"};

  std::vector<std::string> models;
  models.reserve(data.size());
  for (const auto& [model, by_metric] : data) models.push_back(model);
  if (models.empty()) throw std::invalid_argument("boxplots: no models");

  const double slot = 0.8 / static_cast<double>(metrics.size());  // x width per metric
  std::vector<std::pair<std::string, std::string>> files;
  std::vector<bool> metric_in_legend(metrics.size(), false);
  std::string plot = "plot 0 with lines dt 2 lc rgb 'gray40' notitle";
  for (std::size_t g = 0; g < models.size(); ++g) {
    const auto& by_metric = data.at(models[g]);
    for (std::size_t m = 0; m < metrics.size(); ++m) {
      auto it = by_metric.find(metrics[m]);
      if (it == by_metric.end()) continue;
      const std::vector<double> values = finite_values(it->second);
      if (values.empty()) continue;
      const std::string id = std::to_string(g) + "_" + std::to_string(m);
      const double x = static_cast<double>(g + 1) - 0.4 + slot * (static_cast<double>(m) + 0.5);
      const std::string colour = m < 3 ? metric_colours[m] : series_colour(m);
      const std::string colours = " lc rgb '" + colour + "' fc rgb '" + colour + "' ";
      const std::string key = metric_in_legend[m] ? std::string("notitle") : "title " + q_figure(metrics[m]);
      metric_in_legend[m] = true;
      const bool few = values.size() < kMinBoxplotValues;
      if (!few) {
        std::string content;
        for (double v : values) content += num_figure(v) + "\n";
        files.emplace_back("box_" + id + ".dat", content);
        plot += ", \\\n     'box_" + id + ".dat' using (" + num_figure(x) + "):1:(" + num_figure(slot * 0.8) +
                ") with boxplot" + colours + key;
      } else {
        files.emplace_back("small_" + id + ".dat", small_box(values, x, slot * 0.8));
        plot += ", \\\n     'small_" + id + ".dat' using 1:2:3:4:5:6 with boxxyerror" + colours + key +
                ", \\\n     'small_" + id + ".dat' using 3:2:($4-$3):(0) with vectors nohead lw 2 lc rgb '" +
                colour + "' notitle";
      }
      if (few || options.points) {
        // Every value as a point over its box (for a small box, the values are the box).
        files.emplace_back("values_" + id + ".dat", value_points(values, x, slot * 0.8));
        plot += ", \\\n     'values_" + id + ".dat' using 1:2 with points pt 7 ps 0.6 lc rgb '" + colour +
                "' notitle";
      } else {
        // Outliers (beyond 1.5 IQR of the quartiles) drawn here, one point per
        // distinct value: gnuplot's own outliers spread many equal values
        // sideways across neighbouring boxes (many seeds reach the same optimum).
        const std::string outliers = boxplot_outliers(values, x);
        if (!outliers.empty()) {
          files.emplace_back("out_" + id + ".dat", outliers);
          plot += ", \\\n     'out_" + id + ".dat' using 1:2 with points pt 7 ps 0.5 lc rgb '" + colour +
                  "' notitle";
        }
      }
    }
  }
  if (files.empty()) throw std::invalid_argument("boxplots: no finite values to plot");

  std::string body;
  body += "set title " + q_figure(title) + " font ',13'\n";
  body += "set xlabel " + q_figure(options.group_label) + "\nset ylabel 'improvement [%]'\n";
  body += "set xrange [0.5:" + num_figure(static_cast<double>(models.size()) + 0.5) + "]\n";
  body += "set xtics " + category_tics(models, 1) + " scale 0\n";
  body += "set grid ytics lc rgb '#e0e0e0'\n";
  body += "set style fill solid 0.35 border\n";
  body += "set style boxplot nooutliers\n";
  body += "set key outside right top box Left reverse width 1\n";
  body += plot + "\n";
  const int width = std::max(800, 300 + 180 * static_cast<int>(models.size()));
  render_png_svg(stem, std::move(files), body, width, 600);
}

// ---------------------------------------------------------------- convergence

ConvergenceBand resample_convergence(const std::vector<std::vector<ConvergencePoint>>& runs) {
  std::vector<std::vector<ConvergencePoint>> sorted;
  std::vector<long> grid;
  for (const auto& run : runs) {
    if (run.empty()) continue;
    auto r = run;
    std::stable_sort(r.begin(), r.end(), [](const ConvergencePoint& a, const ConvergencePoint& b) {
      return a.evaluations < b.evaluations;
    });
    for (const auto& p : r) grid.push_back(p.evaluations);
    sorted.push_back(std::move(r));
  }
  std::sort(grid.begin(), grid.end());
  grid.erase(std::unique(grid.begin(), grid.end()), grid.end());

  ConvergenceBand band;
  std::vector<std::size_t> cursor(sorted.size(), 0);  // next point index per run
  std::vector<double> at;
  for (long e : grid) {
    at.clear();
    for (std::size_t i = 0; i < sorted.size(); ++i) {
      const auto& r = sorted[i];
      while (cursor[i] < r.size() && r[cursor[i]].evaluations <= e) ++cursor[i];
      if (cursor[i] > 0) at.push_back(r[cursor[i] - 1].best_fitness);
    }
    if (at.empty()) continue;
    std::sort(at.begin(), at.end());
    const std::size_t n = at.size();
    band.evaluations.push_back(e);
    band.median_m.push_back(core::sorted_median(at));
    band.min_m.push_back(at.front());
    band.max_m.push_back(at.back());
    band.runs.push_back(static_cast<int>(n));
  }
  return band;
}

void convergence(const fs::path& stem, const std::string& title,
                 const std::map<std::string, std::vector<std::vector<ConvergencePoint>>>& series) {
  std::vector<std::pair<std::string, std::string>> files;
  std::string plot = "plot ";
  std::size_t k = 0;
  for (const auto& [name, runs] : series) {
    const ConvergenceBand band = resample_convergence(runs);
    if (band.evaluations.empty()) continue;
    // Step-wise rows: at each new grid point first the previous values, then
    // the new ones, so straight segments draw the steps. Columns: e med min max.
    std::string content;
    for (std::size_t i = 0; i < band.evaluations.size(); ++i) {
      const std::string e = std::to_string(band.evaluations[i]) + " ";
      if (i > 0) {
        content += e + num_figure(band.median_m[i - 1]) + " " + num_figure(band.min_m[i - 1]) + " " +
                   num_figure(band.max_m[i - 1]) + "\n";
      }
      content += e + num_figure(band.median_m[i]) + " " + num_figure(band.min_m[i]) + " " +
                 num_figure(band.max_m[i]) + "\n";
    }
    std::size_t nruns = 0;
    for (const auto& r : runs) nruns += r.empty() ? 0 : 1;
    const std::string file = "series_" + std::to_string(k) + ".dat";
    files.emplace_back(file, content);
    const std::string colour = series_colour(k);
    if (k > 0) plot += ", \\\n     ";
    plot += "'" + file + "' using 1:3:4 with filledcurves lc rgb '" + colour + "' title " +
            q_figure(name + " min–max (" + std::to_string(nruns) + (nruns == 1 ? " run)" : " runs)")) +
            ", \\\n     '" + file + "' using 1:2 with lines lw 2 lc rgb '" + colour + "' title " +
            q_figure(name + " median");
    ++k;
  }
  if (files.empty()) throw std::invalid_argument("convergence: no series has a point");

  std::string body;
  body += "set title " + q_figure(title) + " font ',13'\n";
  body += "set xlabel 'evaluations'\nset ylabel 'best fitness [m]'\n";
  body += "set grid lc rgb '#e0e0e0'\n";
  body += "set style fill transparent solid 0.25 noborder\n";
  // The legend beside the plot, not over the curves (a flat curve at the top
  // ran under it), and 5 % of the height above and below the data so no
  // curve lies on the border.
  body += "set key outside right top box Left reverse width 1\n";
  body += "set offsets 0, 0, graph 0.05, graph 0.05\n";
  body += plot + "\n";
  render_png_svg(stem, std::move(files), body, 1000, 600);
}

// ---------------------------------------------------------------- trajectories

namespace {

// The plot area of an x–y figure at equal scale: the data's bounding box
// with a margin of 3 % of its larger side, widened (centred) where the area
// would be lower than kMinSidePx or narrower than that or `min_width_px`,
// and the area's size in pixels.
struct EqualScaleFrame {
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  int width_px = 0, height_px = 0;
};
EqualScaleFrame equal_scale_frame(double x_min, double x_max, double y_min, double y_max, double min_width_px) {
  constexpr double kMaxWidthPx = 820, kMaxHeightPx = 680, kMinSidePx = 220;
  double sx = x_max - x_min, sy = y_max - y_min;
  const double margin = std::max(0.03 * std::max(sx, sy), 1e-3);
  sx += 2 * margin;
  sy += 2 * margin;
  const double cx = 0.5 * (x_min + x_max), cy = 0.5 * (y_min + y_max);
  // Pixels per metre: the largest that fits both maxima.
  const double scale = std::min(kMaxWidthPx / sx, kMaxHeightPx / sy);
  sx = std::max(sx, std::max(kMinSidePx, min_width_px) / scale);
  sy = std::max(sy, kMinSidePx / scale);
  return {cx - sx / 2,
          cx + sx / 2,
          cy - sy / 2,
          cy + sy / 2,
          static_cast<int>(std::lround(sx * scale)),
          static_cast<int>(std::lround(sy * scale))};
}

}  // namespace

void trajectories(const fs::path& stem, const std::string& title, const std::vector<TrajectoryPath>& paths) {
  if (paths.empty()) throw std::invalid_argument("trajectories: no paths");
  std::vector<std::pair<std::string, std::string>> files;
  std::string plot = "plot ";
  double x_min = HUGE_VAL, x_max = -HUGE_VAL, y_min = HUGE_VAL, y_max = -HUGE_VAL;
  std::size_t longest_name = 0, drawn = 0;
  for (std::size_t i = 0; i < paths.size(); ++i) {
    const auto& p = paths[i];
    if (p.xs_m.size() != p.ys_m.size()) {
      throw std::invalid_argument("trajectories: path '" + p.name + "' has " + std::to_string(p.xs_m.size()) +
                                  " x values but " + std::to_string(p.ys_m.size()) + " y values");
    }
    std::string content;
    bool gap = false;
    for (std::size_t j = 0; j < p.xs_m.size(); ++j) {
      if (!std::isfinite(p.xs_m[j]) || !std::isfinite(p.ys_m[j])) {
        if (!gap && !content.empty()) content += "\n";  // a blank line breaks the line
        gap = true;
        continue;
      }
      gap = false;
      content += num_figure(p.xs_m[j]) + " " + num_figure(p.ys_m[j]) + "\n";
      x_min = std::min(x_min, p.xs_m[j]);
      x_max = std::max(x_max, p.xs_m[j]);
      y_min = std::min(y_min, p.ys_m[j]);
      y_max = std::max(y_max, p.ys_m[j]);
    }
    if (content.empty()) continue;
    ++drawn;
    longest_name = std::max(longest_name, p.name.size());
    const std::string file = "path_" + std::to_string(i) + ".dat";
    files.emplace_back(file, content);
    const std::string colour = i == 0 ? "#000000" : series_colour(i - 1);
    if (plot != "plot ") plot += ", \\\n     ";
    plot += "'" + file + "' using 1:2 with lines lw " + (i == 0 ? "2.5" : "1.5") + " lc rgb '" + colour +
            "' title " + q_figure(p.name);
  }
  if (drawn == 0) throw std::invalid_argument("trajectories: no finite point in any path");

  // Equal scale with the plot area fitted to the data: explicit ranges (no
  // widening to whole tics), the area placed in pixels, the canvas sized
  // around it (title above, axis labels left and below, the legend on the
  // right), and `size ratio -1` holding the scale exactly.
  constexpr int kLeftPx = 90, kTopPx = 50, kBottomPx = 65, kKeyRowPx = 20;
  // gnuplot's own estimate of the legend's width (its box) at the SVG's 12 pt.
  const int key_px = 80 + static_cast<int>(9.5 * static_cast<double>(longest_name));
  // The title is centred on the canvas, which is made wide enough for it.
  const double title_px = 40 + 8.0 * static_cast<double>(title.size());
  const EqualScaleFrame f = equal_scale_frame(x_min, x_max, y_min, y_max, title_px - kLeftPx - key_px);
  const int width = kLeftPx + f.width_px + key_px;
  const int height = std::max(kTopPx + f.height_px + kBottomPx,
                              kTopPx + kKeyRowPx * static_cast<int>(drawn) + 30);
  const auto at_x = [width](int px) { return num_figure(static_cast<double>(px) / width); };
  const auto at_y = [height](int px_from_top) {
    return num_figure(1.0 - static_cast<double>(px_from_top) / height);
  };

  std::string body;
  body += "set label 1 " + q_figure(title) + " at screen 0.5, screen " + at_y(kTopPx / 2) +
          " center font ',13'\n";
  body += "set xlabel 'x [m]'\nset ylabel 'y [m]'\n";
  body += "set xrange [" + num_figure(f.x0) + ":" + num_figure(f.x1) + "]\nset yrange [" + num_figure(f.y0) +
          ":" + num_figure(f.y1) + "]\n";
  body += "set lmargin at screen " + at_x(kLeftPx) + "\nset rmargin at screen " + at_x(kLeftPx + f.width_px) +
          "\n";
  body += "set tmargin at screen " + at_y(kTopPx) + "\nset bmargin at screen " + at_y(kTopPx + f.height_px) +
          "\n";
  body += "set size ratio -1\n";
  body += "set grid lc rgb '#e0e0e0'\n";
  body += "set key at screen " + at_x(kLeftPx + f.width_px + 15) + ", screen " + at_y(kTopPx) +
          " left top box Left reverse width 1\n";
  body += plot + "\n";
  render_png_svg(stem, std::move(files), body, width, height);
}

}  // namespace odotune::results

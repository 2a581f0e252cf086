#include <odotune/results/diagnosis_figures.h>

#include <odotune/core/robust_stats.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <odotune/results/gnuplot.h>

namespace odotune::results {
namespace fs = std::filesystem;

namespace {

// Colour-blind-safe colours (Okabe & Ito 2008).
constexpr const char* kBefore = "#D55E00";        // vermillion
constexpr const char* kBeforeMedian = "#8C3D00";  // darker vermillion
constexpr const char* kAfter = "#0072B2";         // blue
constexpr const char* kAfterMedian = "#003F63";   // darker blue
constexpr const char* kSegment = "#E69F00";       // orange, translucent
constexpr const char* kFlagged = "#E41A1C";       // red
constexpr const char* kRegion = "#0072B2";        // blue outline
constexpr const char* kWindow = "#808080";        // grey

// The scatter of figure 2 draws at most this many points per series.
constexpr std::size_t kMaxScatterPoints = 5000;
// Quantile bins of the median trend (figure 2).
constexpr int kMedianBins = 15;

std::string num(double v) { return gnuplot_number(v); }

std::string q(const std::string& s) { return gnuplot_quote(s); }

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument("diagnosis figures: " + what); }

// `field` must have as many values as `ref_field` (or be empty when
// `may_be_empty`).
template <typename T>
void check_length(const std::vector<T>& v, const char* field, std::size_t n, const char* ref_field,
                  bool may_be_empty) {
  if (v.size() == n || (may_be_empty && v.empty())) return;
  bad(std::string(field) + " has " + std::to_string(v.size()) + " values but " + ref_field + " has " +
      std::to_string(n) + (may_be_empty ? " (expected the same or none)" : ""));
}

bool any_finite_pair(const std::vector<double>& a, const std::vector<double>& b) {
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
    if (std::isfinite(a[i]) && std::isfinite(b[i])) return true;
  return false;
}

// Checks every block of `d` (see diagnosis_figures() in the header).
void validate(const DiagnosisFigureData& d) {
  if (d.t_s.empty()) bad("t_s is empty (no reference samples)");
  check_length(d.before_pos_err_m, "before_pos_err_m", d.t_s.size(), "t_s", false);
  check_length(d.after_pos_err_m, "after_pos_err_m", d.t_s.size(), "t_s", true);
  if (!any_finite_pair(d.t_s, d.before_pos_err_m)) bad("before_pos_err_m has no finite value at a finite time");
  for (std::size_t i = 0; i < d.segments.size(); ++i) {
    const TimeSpan& s = d.segments[i];
    if (!std::isfinite(s.t0_s) || !std::isfinite(s.t1_s) || s.t1_s < s.t0_s)
      bad("segments[" + std::to_string(i) + "] = [" + num(s.t0_s) + ", " + num(s.t1_s) +
          "] s is not a finite span with t0_s <= t1_s");
  }
  for (std::size_t i = 0; i < d.window_starts_s.size(); ++i)
    if (!std::isfinite(d.window_starts_s[i])) bad("window_starts_s[" + std::to_string(i) + "] is not finite");

  if (!d.condition_value.empty()) {
    check_length(d.before_residual, "before_residual", d.condition_value.size(), "condition_value", false);
    check_length(d.after_residual, "after_residual", d.condition_value.size(), "condition_value", true);
    if (!any_finite_pair(d.condition_value, d.before_residual))
      bad("no row has a finite condition_value and before_residual");
  } else if (!d.before_residual.empty() || !d.after_residual.empty()) {
    bad("before_residual has " + std::to_string(d.before_residual.size()) + " values and after_residual " +
        std::to_string(d.after_residual.size()) + " but condition_value has 0");
  }

  check_length(d.ref_y_m, "ref_y_m", d.ref_x_m.size(), "ref_x_m", false);
  check_length(d.flagged, "flagged", d.ref_x_m.size(), "ref_x_m", true);
  if (!any_finite_pair(d.ref_x_m, d.ref_y_m)) bad("the reference path (ref_x_m, ref_y_m) has no finite point");
  for (std::size_t i = 0; i < d.regions.size(); ++i) {
    const MapBox& b = d.regions[i];
    const bool finite = std::isfinite(b.x0_m) && std::isfinite(b.x1_m) && std::isfinite(b.y0_m) &&
                        std::isfinite(b.y1_m);
    if (!finite || b.x1_m < b.x0_m || b.y1_m < b.y0_m)
      bad("regions[" + std::to_string(i) + "] = x [" + num(b.x0_m) + ", " + num(b.x1_m) + "] m, y [" +
          num(b.y0_m) + ", " + num(b.y1_m) + "] m is not a finite box with x0 <= x1 and y0 <= y1");
  }

  if (d.overlay.empty()) bad("overlay has no path");
  bool any = false;
  for (const auto& p : d.overlay) {
    if (p.xs_m.size() != p.ys_m.size())
      bad("overlay path '" + p.name + "' has " + std::to_string(p.xs_m.size()) + " xs_m values but " +
          std::to_string(p.ys_m.size()) + " ys_m values");
    any = any || any_finite_pair(p.xs_m, p.ys_m);
  }
  if (!any) bad("no overlay path has a finite point");
}

// "x y" rows of the finite pairs; a blank line where a pair is not finite
// (breaks a line plot).
std::string xy_rows(const std::vector<double>& x, const std::vector<double>& y) {
  std::string out;
  bool gap = false;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
      if (!gap && !out.empty()) out += "\n";
      gap = true;
      continue;
    }
    gap = false;
    out += num(x[i]) + " " + num(y[i]) + "\n";
  }
  return out;
}

// Linear-interpolated quantile p of sorted `v` (non-empty).
double quantile_sorted(const std::vector<double>& v, double p) {
  const double pos = p * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(pos);
  const double f = pos - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] + f * (v[i + 1] - v[i]) : v[i];
}

// A legend below the plot, one entry per line, with the bottom margin
// reserved for it (gnuplot would otherwise draw the x label over the box).
std::string key_below(int entries) {
  return "set key outside below center box Left reverse maxcols 1\nset bmargin " + std::to_string(5 + entries) +
         "\n";
}

std::string with_finding(const std::string& finding) { return finding.empty() ? "corrected model" : finding; }

// ---------------------------------------------------------------- figure 1

void residual_time(const fs::path& stem, const DiagnosisFigureData& d) {
  double t_min = std::numeric_limits<double>::infinity(), t_max = -std::numeric_limits<double>::infinity();
  for (double t : d.t_s)
    if (std::isfinite(t)) t_min = std::min(t_min, t), t_max = std::max(t_max, t);
  if (t_max <= t_min) t_min -= 0.5, t_max += 0.5;
  bool all_nonneg = true;
  for (const auto* v : {&d.before_pos_err_m, &d.after_pos_err_m})
    for (double e : *v)
      if (std::isfinite(e) && e < 0) all_nonneg = false;

  std::string body;
  body += "set title " + q(d.track + ": position error of the window replay vs time") + " font ',13'\n";
  body += "set xlabel 'time [s]'\nset ylabel 'position error [m]'\n";
  body += "set xrange [" + num(t_min) + ":" + num(t_max) + "]\n";
  if (all_nonneg) body += "set yrange [0:*]\n";
  body += "set grid lc rgb '#e0e0e0'\n";
  int tag = 1;
  bool any_segment = false;
  for (const TimeSpan& s : d.segments) {
    const double a = std::max(s.t0_s, t_min), b = std::min(s.t1_s, t_max);
    if (b < a) continue;  // outside the track's time range
    any_segment = true;
    body += "set object " + std::to_string(tag++) + " rectangle from first " + num(a) + ", graph 0 to first " +
            num(b) + ", graph 1 behind fc rgb '" + kSegment + "' fs transparent solid 0.25 noborder\n";
  }
  bool any_window = false;
  for (double w : d.window_starts_s) {
    if (w < t_min || w > t_max) continue;
    any_window = true;
    body += "set arrow from first " + num(w) + ", graph 0 to first " + num(w) +
            ", graph 1 nohead back lw 0.7 dt 3 lc rgb '" + kWindow + "'\n";
  }

  std::vector<std::pair<std::string, std::string>> files = {{"before.dat", xy_rows(d.t_s, d.before_pos_err_m)}};
  std::string plot = "plot 'before.dat' using 1:2 with lines lw 1.5 lc rgb '" + std::string(kBefore) +
                     "' title 'before: nominal model'";
  int entries = 1 + (any_segment ? 1 : 0) + (any_window ? 1 : 0);
  if (!d.after_pos_err_m.empty()) {
    std::string rows = xy_rows(d.t_s, d.after_pos_err_m);
    if (!rows.empty()) {
      files.emplace_back("after.dat", std::move(rows));
      ++entries;
      plot += ", \\\n     'after.dat' using 1:2 with lines lw 1.5 lc rgb '" + std::string(kAfter) + "' title " +
              q("after: " + with_finding(d.finding));
    }
  }
  if (any_segment)
    plot += ", \\\n     keyentry with boxes fc rgb '" + std::string(kSegment) +
            "' fs transparent solid 0.25 noborder title 'located segment'";
  if (any_window)
    plot += ", \\\n     keyentry with lines lw 0.7 dt 3 lc rgb '" + std::string(kWindow) +
            "' title 'window start (replay re-anchored)'";
  body += key_below(entries) + plot + "\n";
  render_png_svg(stem, std::move(files), body, 1100, 560 + 18 * entries);
}

// ---------------------------------------------------------------- figure 2

// Scatter rows of the finite (condition, residual) pairs, every `step`-th
// (deterministic) so that at most kMaxScatterPoints remain; `total` = number
// of finite pairs.
std::string scatter_rows(const std::vector<double>& x, const std::vector<double>& y, std::size_t* step,
                         std::size_t* total) {
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (std::isfinite(x[i]) && std::isfinite(y[i])) rows.push_back(i);
  *total = rows.size();
  *step = std::max<std::size_t>(1, (rows.size() + kMaxScatterPoints - 1) / kMaxScatterPoints);
  std::string out;
  for (std::size_t j = 0; j < rows.size(); j += *step) out += num(x[rows[j]]) + " " + num(y[rows[j]]) + "\n";
  return out;
}

std::string points_title(const std::string& what, std::size_t step, std::size_t total) {
  const std::string rows = std::to_string(total) + (total == 1 ? " row" : " rows");
  return step == 1 ? what + ", " + rows : what + ", " + rows + " (1 in " + std::to_string(step) + " shown)";
}

void residual_condition(const fs::path& stem, const DiagnosisFigureData& d) {
  std::vector<std::pair<std::string, std::string>> files;
  std::string points, medians;
  std::vector<double> plotted;  // all finite residuals shown, for the y range
  const struct {
    const std::vector<double>* y;
    const char* name;
    const char* colour;
    const char* median_colour;
    std::string what;
  } series[] = {{&d.before_residual, "before", kBefore, kBeforeMedian, "before: nominal model"},
                {&d.after_residual, "after", kAfter, kAfterMedian, "after: " + with_finding(d.finding)}};
  for (const auto& s : series) {
    if (s.y->empty()) continue;
    std::size_t step = 1, total = 0;
    std::string rows = scatter_rows(d.condition_value, *s.y, &step, &total);
    if (rows.empty()) continue;
    for (std::size_t i = 0; i < s.y->size(); ++i)
      if (std::isfinite(d.condition_value[i]) && std::isfinite((*s.y)[i])) plotted.push_back((*s.y)[i]);
    const std::string pts = std::string(s.name) + "_points.dat";
    const std::string med = std::string(s.name) + "_median.dat";
    files.emplace_back(pts, std::move(rows));
    const BinnedMedian bm = binned_median(d.condition_value, *s.y, kMedianBins);
    files.emplace_back(med, xy_rows(bm.x, bm.y));
    // Translucent points (gnuplot's #AARRGGBB: AA = transparency).
    points += ", \\\n     '" + pts + "' using 1:2 with points pt 7 ps 0.3 lc rgb '#B0" +
              std::string(s.colour + 1) + "' title " + q(points_title(s.what, step, total));
    medians += ", \\\n     '" + med + "' using 1:2 with linespoints lw 2.5 pt 5 ps 0.9 lc rgb '" +
               s.median_colour + "' title " +
               q(std::string(s.name) + ": median in " + std::to_string(bm.x.size()) +
                 " quantile bins of the condition");
  }

  std::string title = d.track + ": " + d.residual_label + " vs " + d.condition_label;
  std::string body;
  // Heavy tails would flatten the trend: with many rows whose extremes lie
  // far beyond the 0.5–99.5 % quantiles, the y axis shows those quantiles.
  std::sort(plotted.begin(), plotted.end());
  if (plotted.size() >= 200) {
    const double lo = quantile_sorted(plotted, 0.005), hi = quantile_sorted(plotted, 0.995);
    const double span = std::max(hi - lo, 1e-12);
    if (plotted.back() - plotted.front() > 3.0 * span) {
      body += "set yrange [" + num(lo - 0.1 * span) + ":" + num(hi + 0.1 * span) + "]\n";
      title += " (y axis: 0.5–99.5 % quantiles)";
    }
  }
  body += "set title " + q(title) + " font ',13'\n";
  body += "set xlabel " + q(d.condition_label) + "\nset ylabel " + q(d.residual_label) + "\n";
  body += "set grid lc rgb '#e0e0e0'\n";
  const int entries = static_cast<int>(files.size());  // points + median per series
  body += key_below(entries);
  body += "plot 0 with lines dt 2 lc rgb 'gray40' notitle" + points + medians + "\n";
  render_png_svg(stem, std::move(files), body, 1000, 640 + 18 * entries);
}

// ---------------------------------------------------------------- figure 3

void map_figure(const fs::path& stem, const DiagnosisFigureData& d) {
  double x0 = std::numeric_limits<double>::infinity(), x1 = -std::numeric_limits<double>::infinity(),
         y0 = std::numeric_limits<double>::infinity(), y1 = -std::numeric_limits<double>::infinity();
  auto extend = [&](double x, double y) {
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  };
  for (std::size_t i = 0; i < d.ref_x_m.size(); ++i)
    if (std::isfinite(d.ref_x_m[i]) && std::isfinite(d.ref_y_m[i])) extend(d.ref_x_m[i], d.ref_y_m[i]);
  for (const MapBox& b : d.regions) extend(b.x0_m, b.y0_m), extend(b.x1_m, b.y1_m);
  // Room for the region labels above the boxes.
  const double pad = std::max(0.5, 0.06 * std::max(x1 - x0, y1 - y0));

  std::string body;
  body += "set title " + q(d.track + ": located regions on the reference path") + " font ',13'\n";
  body += "set xlabel 'x [m]'\nset ylabel 'y [m]'\n";
  body += "set size ratio -1\n";
  body += "set xrange [" + num(x0 - pad) + ":" + num(x1 + pad) + "]\n";
  body += "set yrange [" + num(y0 - pad) + ":" + num(y1 + pad) + "]\n";
  body += "set grid lc rgb '#e0e0e0'\n";
  body += "set key outside right top box Left reverse width 1\n";
  for (std::size_t i = 0; i < d.regions.size(); ++i) {
    const MapBox& b = d.regions[i];
    const std::string tag = std::to_string(i + 1);
    body += "set object " + tag + " rectangle from " + num(b.x0_m) + "," + num(b.y0_m) + " to " + num(b.x1_m) +
            "," + num(b.y1_m) + " front fs empty border lc rgb '" + kRegion + "' lw 2\n";
    body += "set label " + tag + " " + q("region " + tag) + " at " + num(b.x0_m) + "," + num(b.y1_m) +
            " left offset 0.2,0.6 front tc rgb '" + kRegion + "'\n";
  }

  std::vector<std::pair<std::string, std::string>> files = {{"ref.dat", xy_rows(d.ref_x_m, d.ref_y_m)}};
  std::string plot = "plot 'ref.dat' using 1:2 with lines lw 1.5 lc rgb '#9A9A9A' title 'reference path'";
  std::string flagged;
  std::size_t n_flagged = 0;
  for (std::size_t i = 0; i < d.flagged.size(); ++i) {
    if (d.flagged[i] == 0 || !std::isfinite(d.ref_x_m[i]) || !std::isfinite(d.ref_y_m[i])) continue;
    flagged += num(d.ref_x_m[i]) + " " + num(d.ref_y_m[i]) + "\n";
    ++n_flagged;
  }
  if (n_flagged > 0) {
    files.emplace_back("flagged.dat", std::move(flagged));
    plot += ", \\\n     'flagged.dat' using 1:2 with points pt 7 ps 0.45 lc rgb '" + std::string(kFlagged) +
            "' title " + q("residual above noise (" + std::to_string(n_flagged) + " samples)");
  }
  if (!d.regions.empty())
    plot += ", \\\n     keyentry with lines lw 2 lc rgb '" + std::string(kRegion) + "' title 'located region'";
  body += plot + "\n";
  render_png_svg(stem, std::move(files), body, 1000, 750);
}

}  // namespace

BinnedMedian binned_median(const std::vector<double>& x, const std::vector<double>& y, int bins) {
  if (x.size() != y.size())
    throw std::invalid_argument("binned_median: x has " + std::to_string(x.size()) + " values but y has " +
                                std::to_string(y.size()));
  if (bins < 1) throw std::invalid_argument("binned_median: bins must be >= 1, got " + std::to_string(bins));
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (std::isfinite(x[i]) && std::isfinite(y[i])) rows.push_back(i);
  std::stable_sort(rows.begin(), rows.end(), [&x](std::size_t a, std::size_t b) { return x[a] < x[b]; });
  BinnedMedian out;
  const std::size_t n = rows.size();
  const std::size_t groups = std::min(n, static_cast<std::size_t>(bins));
  std::size_t begin = 0;
  std::vector<double> gx, gy;
  for (std::size_t g = 0; g < groups; ++g) {
    const std::size_t count = n / groups + (g < n % groups ? 1 : 0);
    gx.clear();
    gy.clear();
    for (std::size_t j = begin; j < begin + count; ++j) {
      gx.push_back(x[rows[j]]);
      gy.push_back(y[rows[j]]);
    }
    out.x.push_back(core::median(gx));
    out.y.push_back(core::median(gy));
    begin += count;
  }
  return out;
}

std::vector<fs::path> diagnosis_figures(const fs::path& dir, const DiagnosisFigureData& data) {
  validate(data);
  std::vector<fs::path> stems;
  stems.push_back(dir / "residual_time");
  residual_time(stems.back(), data);
  if (!data.condition_value.empty()) {
    stems.push_back(dir / "residual_condition");
    residual_condition(stems.back(), data);
  }
  stems.push_back(dir / "map");
  map_figure(stems.back(), data);
  stems.push_back(dir / "overlay");
  trajectories(stems.back(),
               data.track + ": trajectory overlay" +
                   (data.finding.empty() ? std::string(" (no finding)") : " (finding: " + data.finding + ")"),
               data.overlay);
  return stems;
}

}  // namespace odotune::results

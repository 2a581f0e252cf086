#include <odotune/results/param_range_figure.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <odotune/results/gnuplot.h>

namespace odotune::results {
namespace fs = std::filesystem;

namespace {

bool positive(double v) { return std::isfinite(v) && v > 0.0; }

std::string n(double v) { return gnuplot_number(v); }

}  // namespace

void param_ranges_figure(const fs::path& stem, const std::string& title, const std::string& x_label,
                         const std::vector<std::string>& params, const std::vector<ParamRangeSeries>& series,
                         double reference, const std::string& reference_label) {
  if (params.empty()) throw std::invalid_argument("param_ranges_figure: no parameters");
  if (series.empty()) throw std::invalid_argument("param_ranges_figure: no series");
  double lo_all = std::numeric_limits<double>::infinity(), hi_all = 0.0;
  const auto widen = [&](double v) {
    if (!positive(v)) return;
    lo_all = std::min(lo_all, v);
    hi_all = std::max(hi_all, v);
  };
  widen(reference);
  for (const ParamRangeSeries& s : series) {
    if (s.values.size() != params.size() || s.ranges.size() != params.size())
      throw std::invalid_argument("param_ranges_figure: series '" + s.name + "' has " +
                                  std::to_string(s.values.size()) + " values and " +
                                  std::to_string(s.ranges.size()) + " ranges for " +
                                  std::to_string(params.size()) + " parameters");
    for (std::size_t i = 0; i < params.size(); ++i) {
      widen(s.values[i]);
      widen(s.ranges[i].lo);
      widen(s.ranges[i].hi);
    }
  }
  if (!(hi_all > 0.0)) throw std::invalid_argument("param_ranges_figure: no positive finite value to draw");
  // The axis in decades, with a margin of 5 % of its span (at least 0.1 decade).
  const double a = std::log10(lo_all), b = std::log10(hi_all);
  const double pad = std::max(0.05 * (b - a), 0.1);
  const double x_min = std::pow(10.0, a - pad), x_max = std::pow(10.0, b + pad);

  const std::size_t ns = series.size();
  const double step = 0.8 / static_cast<double>(ns);  // row height per series
  const double half = 0.3 * step;                     // half a bar's height
  // A "not determined" label beside its bar, 1 % of the axis away, on the
  // right if there is room, else on the left, else on the bar.
  const double nudge = std::pow(10.0, 0.01 * (b - a + 2 * pad));
  std::vector<std::string> bars(ns), pale(ns);
  std::string dots, labels_right, labels_left, labels_centre;
  for (std::size_t k = 0; k < ns; ++k) {
    const ParamRangeSeries& s = series[k];
    for (std::size_t i = 0; i < params.size(); ++i) {
      const double y = static_cast<double>(i) +
                       (static_cast<double>(k) - 0.5 * static_cast<double>(ns - 1)) * step;
      const ParamRange& r = s.ranges[i];
      // A bound that cannot be drawn on the log axis goes to its edge.
      const double lo = positive(r.lo) ? r.lo : x_min;
      const double hi = positive(r.hi) ? r.hi : x_max;
      const double x0 = std::min(lo, hi), x1 = std::max(lo, hi);
      const std::string bar = n(std::sqrt(x0 * x1)) + " " + n(y) + " " + n(x0) + " " + n(x1) + " " +
                              n(y - half) + " " + n(y + half) + "\n";
      if (r.determined) {
        bars[k] += bar;
      } else {
        pale[k] += bar;
        const double total = b - a + 2 * pad;
        if ((b + pad) - std::log10(x1) >= 0.15 * total)
          labels_right += n(x1 * nudge) + " " + n(y) + " \"not determined\"\n";
        else if (std::log10(x0) - (a - pad) >= 0.15 * total)
          labels_left += n(x0 / nudge) + " " + n(y) + " \"not determined\"\n";
        else
          labels_centre += n(std::sqrt(x0 * x1)) + " " + n(y) + " \"not determined\"\n";
      }
      if (positive(s.values[i])) dots += n(s.values[i]) + " " + n(y) + "\n";
    }
  }

  std::vector<std::pair<std::string, std::string>> files;
  std::string plot = "plot ";
  auto add = [&plot](const std::string& clause) {
    if (plot != "plot ") plot += ", \\\n     ";
    plot += clause;
  };
  bool any_pale = false;
  for (std::size_t k = 0; k < ns; ++k) {
    const std::string colour = series_colour(static_cast<int>(k));
    const std::string file = "bars_" + std::to_string(k) + ".dat";
    // A series with no determined range keeps its legend entry: a NaN row draws nothing.
    files.emplace_back(file, bars[k].empty() ? "NaN NaN NaN NaN NaN NaN\n" : bars[k]);
    add("'" + file + "' using 1:2:3:4:5:6 with boxxyerror fs solid 0.8 noborder lc rgb '" + colour +
        "' fc rgb '" + colour + "' title " + gnuplot_quote(series[k].name));
    if (pale[k].empty()) continue;
    // Not determined: the series' colour, pale, with a dashed outline.
    const std::string pale_file = "pale_" + std::to_string(k) + ".dat";
    files.emplace_back(pale_file, pale[k]);
    add("'" + pale_file + "' using 1:2:3:4:5:6 with boxxyerror fs solid 0.2 border lc rgb '" + colour +
        "' fc rgb '" + colour + "' dt 2 notitle");
    any_pale = true;
  }
  if (any_pale)
    add("NaN with boxes fs solid 0.2 border lc rgb '#808080' fc rgb '#808080' dt 2 title "
        "'not determined (pale, dashed)'");
  if (!labels_right.empty()) {
    files.emplace_back("labels_r.dat", labels_right);
    add("'labels_r.dat' using 1:2:3 with labels left font ',9' tc rgb '#606060' notitle");
  }
  if (!labels_left.empty()) {
    files.emplace_back("labels_l.dat", labels_left);
    add("'labels_l.dat' using 1:2:3 with labels right font ',9' tc rgb '#606060' notitle");
  }
  if (!labels_centre.empty()) {
    files.emplace_back("labels_c.dat", labels_centre);
    add("'labels_c.dat' using 1:2:3 with labels center font ',9' tc rgb '#404040' notitle");
  }
  if (positive(reference)) {
    files.emplace_back("reference.dat", n(reference) + " -0.5\n" + n(reference) + " " +
                                            n(static_cast<double>(params.size()) - 0.5) + "\n");
    add("'reference.dat' using 1:2 with lines dt 2 lw 1.5 lc rgb '#404040' title " +
        gnuplot_quote(reference_label));
  }
  if (!dots.empty()) {
    files.emplace_back("dots.dat", dots);
    add("'dots.dat' using 1:2 with points pt 7 ps 0.8 lc rgb 'black' title 'tuned value'");
  }

  std::string ytics = "(";
  for (std::size_t i = 0; i < params.size(); ++i)
    ytics += (i ? ", " : "") + gnuplot_quote(params[i]) + " " + std::to_string(i);
  ytics += ")";

  std::string body;
  body += "set title " + gnuplot_quote(title) + " font ',13'\n";
  body += "set xlabel " + gnuplot_quote(x_label) + "\n";
  body += "set logscale x 10\nset format x '%g'\n";
  body += "set xrange [" + n(x_min) + ":" + n(x_max) + "]\n";
  body += "set yrange [" + n(static_cast<double>(params.size()) - 0.5) + ":-0.5]\n";
  body += "set ytics " + ytics + " scale 0\n";
  body += "set grid xtics mxtics lc rgb '#e8e8e8'\n";
  for (std::size_t i = 1; i < params.size(); ++i)  // a light line between parameters
    body += "set arrow from graph 0, first " + n(static_cast<double>(i) - 0.5) + " to graph 1, first " +
            n(static_cast<double>(i) - 0.5) + " nohead lc rgb '#d8d8d8' back\n";
  // The legend in two rows at the foot of the canvas, below the x label.
  body +=
      "set bmargin 7\nset key at screen 0.5, screen 0.01 center bottom horizontal maxcols 3 box Left reverse "
      "width 1\n";
  body += plot + "\n";
  const int height = std::max(360, 200 + static_cast<int>(params.size()) * (14 * static_cast<int>(ns) + 14));
  render_png_svg(stem, std::move(files), body, 1000, height);
}

}  // namespace odotune::results

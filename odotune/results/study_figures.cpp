#include <odotune/results/study_figures.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <odotune/results/gnuplot.h>

namespace odotune::results {
namespace fs = std::filesystem;

namespace {

std::string num_study(double v) { return gnuplot_number(v); }

std::string q_study(const std::string& s) { return gnuplot_quote(s); }

[[noreturn]] void bad_study(const std::string& what) { throw std::invalid_argument("study figure: " + what); }

}  // namespace

// ---------------------------------------------------------------- grouped bars

void grouped_bars(const fs::path& stem, const std::string& title, const std::vector<std::string>& groups,
                  const std::vector<std::string>& series, const std::vector<BarPanel>& panels) {
  if (groups.empty()) bad_study("grouped bars: no groups");
  if (series.empty()) bad_study("grouped bars: no series");
  if (panels.empty()) bad_study("grouped bars: no panels");
  bool any = false;
  for (const BarPanel& p : panels) {
    if (p.mean.size() != groups.size() || p.sd.size() != groups.size())
      bad_study("grouped bars: panel '" + p.ylabel + "' has " + std::to_string(p.mean.size()) +
                " mean rows and " + std::to_string(p.sd.size()) + " sd rows, expected " +
                std::to_string(groups.size()) + " (one per group)");
    for (std::size_t g = 0; g < groups.size(); ++g) {
      if (p.mean[g].size() != series.size() || p.sd[g].size() != series.size())
        bad_study("grouped bars: panel '" + p.ylabel + "', group '" + groups[g] + "' has " +
                  std::to_string(p.mean[g].size()) + " means and " + std::to_string(p.sd[g].size()) +
                  " sds, expected " + std::to_string(series.size()) + " (one per series)");
      for (double v : p.mean[g]) any = any || std::isfinite(v);
    }
  }
  if (!any) bad_study("grouped bars: no finite value");

  const double slot = 0.8 / static_cast<double>(series.size());  // width of one bar's slot
  std::vector<std::pair<std::string, std::string>> files;
  std::string body = "reset\nset multiplot title " + q_study(title) + " font ',13'\n";
  body += "set style fill solid 0.75 border lc rgb '#303030'\n";
  body += "set boxwidth " + num_study(slot * 0.9) + " absolute\n";
  body += "set errorbars lc rgb '#000000' lw 1.2\n";
  body += "set grid ytics lc rgb '#e0e0e0'\n";
  body += "set xrange [-0.5:" + num_study(static_cast<double>(groups.size()) - 0.5) + "]\n";
  body += "set lmargin at screen 0.10\nset rmargin at screen 0.80\n";
  body += "set key outside right top Left reverse\n";
  body += "set format y '%.3g'\n";
  std::string tics = "(";
  for (std::size_t g = 0; g < groups.size(); ++g)
    tics += (g ? ", " : "") + q_study(groups[g]) + " " + std::to_string(g);
  tics += ")";
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const auto [top, bottom] = stacked_panel_span(p, panels.size());
    body += "set tmargin at screen " + num_study(top) + "\nset bmargin at screen " + num_study(bottom) + "\n";
    body += "set ylabel " + q_study(panels[p].ylabel) + "\n";
    body += "set xtics " + tics + "\n";
    body += p + 1 == panels.size() ? "set format x '%g'\n" : "set format x ''\n";
    body += "set yrange [0:*]\n";
    std::string plot;
    for (std::size_t s = 0; s < series.size(); ++s) {
      std::string rows;
      for (std::size_t g = 0; g < groups.size(); ++g) {
        const double m = panels[p].mean[g][s], sd = panels[p].sd[g][s];
        if (!std::isfinite(m)) continue;
        const double x = static_cast<double>(g) - 0.4 + slot * (static_cast<double>(s) + 0.5);
        rows += num_study(x) + " " + num_study(m) + " " + num_study(std::isfinite(sd) ? sd : 0.0) + "\n";
      }
      if (rows.empty()) continue;
      const std::string file = "p" + std::to_string(p) + "s" + std::to_string(s) + ".dat";
      files.emplace_back(file, rows);
      plot += (plot.empty() ? "plot " : ", \\\n     ") +
              ("'" + file + "' using 1:2:3 with boxerrorbars lc rgb '" + series_colour(static_cast<int>(s)) +
               "' title " + (p == 0 ? q_study(series[s]) : "''"));
    }
    if (plot.empty()) plot = "plot NaN notitle";
    body += plot + "\n";
  }
  body += "unset multiplot\n";
  render_png_svg(stem, std::move(files), body, 1100, 380 + 260 * static_cast<int>(panels.size()));
}

// ---------------------------------------------------------------- time panels

std::string time_marker_labels(const std::vector<TimeMarker>& markers) {
  std::string out;
  int tag = 1;
  for (const TimeMarker& m : markers)
    if (!m.label.empty())
      out += "set label " + std::to_string(tag++) + " " + q_study(m.label) + " at first " + num_study(m.t_s) +
             ", graph 1 left offset 0.4,-1 front tc rgb '#404040' font ',9'\n";
  return out;
}

void time_panels(const fs::path& stem, const std::string& title, const std::vector<TimePanel>& panels,
                 const std::vector<TimeMarker>& markers) {
  if (panels.empty()) bad_study("time panels: no panel");
  double t_min = std::numeric_limits<double>::infinity(), t_max = -std::numeric_limits<double>::infinity();
  for (const TimePanel& p : panels) {
    bool any = false;
    for (const PanelLine& l : p.lines) {
      if (l.t_s.size() != l.y.size())
        bad_study("panel '" + p.ylabel + "', line '" + l.name + "' has " + std::to_string(l.t_s.size()) +
                  " times but " + std::to_string(l.y.size()) + " values");
      for (std::size_t i = 0; i < l.t_s.size(); ++i)
        if (std::isfinite(l.t_s[i]) && std::isfinite(l.y[i])) {
          any = true;
          t_min = std::min(t_min, l.t_s[i]);
          t_max = std::max(t_max, l.t_s[i]);
        }
    }
    if (!any) bad_study("panel '" + p.ylabel + "' has no finite point");
  }
  for (const TimeMarker& m : markers)
    if (!std::isfinite(m.t_s)) bad_study("a marker time is not finite");
  if (t_max <= t_min) t_min -= 0.5, t_max += 0.5;

  std::vector<std::pair<std::string, std::string>> files;
  std::string body = "reset\nset multiplot title " + q_study(title) + " font ',13'\n";
  body += "set grid lc rgb '#e0e0e0'\n";
  body += "set xrange [" + num_study(t_min) + ":" + num_study(t_max) + "]\n";
  body += "set key outside right top Left reverse\n";
  body += "set lmargin at screen 0.10\nset rmargin at screen 0.76\n";
  body += "set format y '%.4g'\n";
  for (const TimeMarker& m : markers)
    body += "set arrow from first " + num_study(m.t_s) + ", graph 0 to first " + num_study(m.t_s) +
            ", graph 1 nohead back lw 1 dt 3 lc rgb '#606060'\n";
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const auto [top, bottom] = stacked_panel_span(p, panels.size());
    body += "set tmargin at screen " + num_study(top) + "\nset bmargin at screen " + num_study(bottom) + "\n";
    body += "set ylabel " + q_study(panels[p].ylabel) + "\n";
    if (p + 1 == panels.size()) {
      body += "set format x '%g'\nset xlabel 'time [s]'\n";
    } else {
      body += "set format x ''\nunset xlabel\n";
    }
    body += "unset label\n";
    if (p == 0) body += time_marker_labels(markers);
    std::string plot;
    for (std::size_t i = 0; i < panels[p].lines.size(); ++i) {
      const PanelLine& l = panels[p].lines[i];
      std::string rows;
      bool gap = false;
      for (std::size_t j = 0; j < l.t_s.size(); ++j) {
        if (!std::isfinite(l.t_s[j]) || !std::isfinite(l.y[j])) {
          if (!gap && !rows.empty()) rows += "\n";
          gap = true;
          continue;
        }
        gap = false;
        rows += num_study(l.t_s[j]) + " " + num_study(l.y[j]) + "\n";
      }
      if (rows.empty()) continue;
      const std::string file = "p" + std::to_string(p) + "l" + std::to_string(i) + ".dat";
      files.emplace_back(file, std::move(rows));
      const std::string width = l.thin ? "1" : "1.8";
      plot += (plot.empty() ? "plot " : ", \\\n     ") +
              ("'" + file + "' using 1:2 with " + (l.dashed ? "steps dt 2" : "lines") + " lw " + width +
               " lc rgb '" + series_colour(l.colour) + "' title " + q_study(l.name));
    }
    body += plot + "\n";
  }
  body += "unset multiplot\n";
  render_png_svg(stem, std::move(files), body, 1150, 300 + 280 * static_cast<int>(panels.size()));
}

}  // namespace odotune::results

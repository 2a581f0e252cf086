#include <odotune/results/learned_figures.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <odotune/results/gnuplot.h>

namespace odotune::results {
namespace fs = std::filesystem;

namespace {

constexpr const char* kShadeColour = "#d9d9d9";  // slip episodes, behind the curves

std::string num_learned(double v) { return gnuplot_number(v); }
std::string q_learned(const std::string& s) { return gnuplot_quote(s); }

[[noreturn]] void bad_learned(const std::string& what) {
  throw std::invalid_argument("learned figure: " + what);
}

bool plottable(double y, bool log_y) { return std::isfinite(y) && (!log_y || y > 0.0); }

// "x y" rows, a blank line where a point is not plottable (gnuplot breaks the line).
std::string rows_of(const std::vector<double>& x, const std::vector<double>& y, bool log_y) {
  std::string rows;
  bool gap = false;
  for (std::size_t j = 0; j < x.size(); ++j) {
    if (!std::isfinite(x[j]) || !plottable(y[j], log_y)) {
      if (!gap && !rows.empty()) rows += "\n";
      gap = true;
      continue;
    }
    gap = false;
    rows += num_learned(x[j]) + " " + num_learned(y[j]) + "\n";
  }
  return rows;
}

}  // namespace

namespace {

// Checks the panels, shades and markers (std::invalid_argument naming the
// bad_learned one) and returns the time range the plottable points span (widened by
// ±0.5 s when empty).
std::pair<double, double> checked_time_range(const std::vector<ShadedPanel>& panels,
                                             const std::vector<TimeShade>& shades,
                                             const std::vector<TimeMarker>& markers) {
  if (panels.empty()) bad_learned("time panels: no panel");
  double t_min = std::numeric_limits<double>::infinity(), t_max = -std::numeric_limits<double>::infinity();
  for (const ShadedPanel& p : panels) {
    bool any = false;
    for (const PanelLine& l : p.lines) {
      if (l.t_s.size() != l.y.size())
        bad_learned("panel '" + p.ylabel + "', line '" + l.name + "' has " + std::to_string(l.t_s.size()) +
                    " times but " + std::to_string(l.y.size()) + " values");
      for (std::size_t i = 0; i < l.t_s.size(); ++i)
        if (std::isfinite(l.t_s[i]) && plottable(l.y[i], p.log_y)) {
          any = true;
          t_min = std::min(t_min, l.t_s[i]);
          t_max = std::max(t_max, l.t_s[i]);
        }
    }
    if (!any) bad_learned("panel '" + p.ylabel + "' has no plottable point");
  }
  for (const TimeShade& s : shades)
    if (!std::isfinite(s.t0_s) || !std::isfinite(s.t1_s) || !(s.t1_s > s.t0_s))
      bad_learned("a shaded interval [" + num_learned(s.t0_s) + ", " + num_learned(s.t1_s) +
                  "] is not finite with t1 > t0");
  for (const TimeMarker& m : markers)
    if (!std::isfinite(m.t_s)) bad_learned("a marker time is not finite");
  if (t_max <= t_min) t_min -= 0.5, t_max += 0.5;
  return {t_min, t_max};
}

// Panel p of the stack: its margins, y axis, x labels on the last, marker
// labels and the shade's key entry on the first, and its lines (their data
// files into `files`).
std::string panel_script(const std::vector<ShadedPanel>& panels, std::size_t p,
                         const std::vector<TimeShade>& shades, const std::string& shade_label,
                         const std::vector<TimeMarker>& markers,
                         std::vector<std::pair<std::string, std::string>>& files) {
  std::string body;
  const ShadedPanel& panel = panels[p];
  const auto [top, bottom] = stacked_panel_span(p, panels.size());
  body += "set tmargin at screen " + num_learned(top) + "\nset bmargin at screen " + num_learned(bottom) + "\n";
  body += "set ylabel " + q_learned(panel.ylabel) + "\n";
  body += panel.log_y ? "set logscale y\nset format y '%.0e'\n" : "unset logscale y\nset format y '%.3g'\n";
  body += std::isfinite(panel.y_min) && (!panel.log_y || panel.y_min > 0.0)
              ? "set yrange [" + num_learned(panel.y_min) + ":*]\n"
              : "set yrange [*:*]\n";
  if (p + 1 == panels.size())
    body += "set format x '%g'\nset xlabel 'time [s]'\n";
  else
    body += "set format x ''\nunset xlabel\n";
  body += "unset label\n";
  if (p == 0) body += time_marker_labels(markers);
  std::string plot;
  for (std::size_t i = 0; i < panel.lines.size(); ++i) {
    const PanelLine& l = panel.lines[i];
    std::string rows = rows_of(l.t_s, l.y, panel.log_y);
    if (rows.empty()) continue;
    const std::string file = "p" + std::to_string(p) + "l" + std::to_string(i) + ".dat";
    files.emplace_back(file, std::move(rows));
    plot += (plot.empty() ? "plot " : ", \\\n     ") +
            ("'" + file + "' using 1:2 with " + (l.dashed ? "steps dt 2" : "lines") + " lw " +
             (l.thin ? "1" : "1.8") + " lc rgb '" + series_colour(l.colour) + "' title " + q_learned(l.name));
  }
  if (p == 0 && !shades.empty() && !shade_label.empty())
    plot += ", \\\n     keyentry with boxes fs solid 1.0 noborder fc rgb '" + std::string(kShadeColour) +
            "' title " + q_learned(shade_label);
  body += plot + "\n";
  return body;
}

}  // namespace

void shaded_time_panels(const fs::path& stem, const std::string& title, const std::vector<ShadedPanel>& panels,
                        const std::vector<TimeShade>& shades, const std::string& shade_label,
                        const std::vector<TimeMarker>& markers) {
  const auto [t_min, t_max] = checked_time_range(panels, shades, markers);

  std::vector<std::pair<std::string, std::string>> files;
  std::string body = "reset\nset multiplot title " + q_learned(title) + " font ',13'\n";
  body += "set grid lc rgb '#e0e0e0'\n";
  body += "set xrange [" + num_learned(t_min) + ":" + num_learned(t_max) + "]\n";
  body += "set key outside right top Left reverse\n";
  body += "set lmargin at screen 0.10\nset rmargin at screen 0.74\n";
  int object = 1;
  for (const TimeShade& s : shades)
    body += "set object " + std::to_string(object++) + " rect from first " + num_learned(s.t0_s) +
            ", graph 0 to first " + num_learned(s.t1_s) + ", graph 1 behind fc rgb '" + kShadeColour +
            "' fs solid 1.0 noborder\n";
  for (const TimeMarker& m : markers)
    body += "set arrow from first " + num_learned(m.t_s) + ", graph 0 to first " + num_learned(m.t_s) +
            ", graph 1 nohead back lw 1 dt 3 lc rgb '#606060'\n";
  for (std::size_t p = 0; p < panels.size(); ++p)
    body += panel_script(panels, p, shades, shade_label, markers, files);
  body += "unset multiplot\n";
  render_png_svg(stem, std::move(files), body, 1150, 300 + 280 * static_cast<int>(panels.size()));
}

void path_panels(const fs::path& stem, const std::string& title, const std::vector<PathPanel>& panels) {
  if (panels.empty()) bad_learned("path panels: no panel");
  for (const PathPanel& p : panels) {
    bool any = false;
    for (const PathLine& l : p.lines) {
      if (l.x_m.size() != l.y_m.size())
        bad_learned("path panel '" + p.title + "', line '" + l.name + "' has " + std::to_string(l.x_m.size()) +
                    " x values but " + std::to_string(l.y_m.size()) + " y values");
      for (std::size_t i = 0; i < l.x_m.size(); ++i)
        any = any || (std::isfinite(l.x_m[i]) && std::isfinite(l.y_m[i]));
    }
    if (!any) bad_learned("path panel '" + p.title + "' has no finite point");
  }

  const std::size_t n = panels.size();
  std::vector<std::pair<std::string, std::string>> files;
  std::string body = "reset\nset multiplot title " + q_learned(title) + " font ',13'\n";
  body += "set grid lc rgb '#e0e0e0'\n";
  body += "set size ratio -1\n";  // equal scales on x and y
  body += "set key below Left reverse\n";
  body += "set xlabel 'x [m]'\nset ylabel 'y [m]'\nset format x '%g'\nset format y '%g'\n";
  constexpr double kLeft = 0.04, kRight = 0.98, kGap = 0.05;
  const double w = (kRight - kLeft - kGap * static_cast<double>(n - 1)) / static_cast<double>(n);
  for (std::size_t p = 0; p < n; ++p) {
    const PathPanel& panel = panels[p];
    const double left = kLeft + static_cast<double>(p) * (w + kGap);
    body += "set lmargin at screen " + num_learned(left + 0.04) + "\nset rmargin at screen " +
            num_learned(left + w) + "\n";
    body += "set tmargin at screen 0.88\nset bmargin at screen 0.22\n";
    body += "set title " + q_learned(panel.title) + "\n";
    std::string plot;
    for (std::size_t i = 0; i < panel.lines.size(); ++i) {
      const PathLine& l = panel.lines[i];
      std::string rows = rows_of(l.x_m, l.y_m, false);
      if (rows.empty()) continue;
      const std::string file = "p" + std::to_string(p) + "l" + std::to_string(i) + ".dat";
      files.emplace_back(file, std::move(rows));
      plot += (plot.empty() ? "plot " : ", \\\n     ") +
              ("'" + file + "' using 1:2 with lines lw 1.6 " + (l.dashed ? "dt 2 " : "") + "lc rgb '" +
               series_colour(l.colour) + "' title " + q_learned(l.name));
    }
    // The start: the first finite point of the first line.
    for (const PathLine& l : panel.lines) {
      bool found = false;
      for (std::size_t i = 0; i < l.x_m.size(); ++i)
        if (std::isfinite(l.x_m[i]) && std::isfinite(l.y_m[i])) {
          const std::string file = "p" + std::to_string(p) + "start.dat";
          files.emplace_back(file, num_learned(l.x_m[i]) + " " + num_learned(l.y_m[i]) + "\n");
          plot += ", \\\n     '" + file + "' using 1:2 with points pt 7 ps 1.2 lc rgb '#000000' title 'start'";
          found = true;
          break;
        }
      if (found) break;
    }
    body += plot + "\n";
  }
  body += "unset multiplot\n";
  render_png_svg(stem, std::move(files), body, 700 * static_cast<int>(n), 720);
}

}  // namespace odotune::results

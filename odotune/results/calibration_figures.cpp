#include <odotune/results/calibration_figures.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <odotune/results/gnuplot.h>

namespace odotune::results {
namespace fs = std::filesystem;

namespace {

// Colour-blind-safe series colours (Okabe & Ito 2008), yellow and black left
// out (black is the default truth colour).
const char* const kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9"};
constexpr int kPaletteSize = static_cast<int>(sizeof(kPalette) / sizeof(kPalette[0]));
constexpr const char* kTruthColour = "#000000";
constexpr const char* kMarkerColour = "#808080";

std::string num_calibration(double v) { return gnuplot_number(v); }

std::string q_calibration(const std::string& s) { return gnuplot_quote(s); }

[[noreturn]] void bad_calibration(const std::string& what) {
  throw std::invalid_argument("calibration figure: " + what);
}

bool finite_point(const EstimateSeries& s, std::size_t i) {
  return std::isfinite(s.t_s[i]) && std::isfinite(s.value_m[i]);
}

void validate_panel(const std::vector<EstimateSeries>& panel, const char* which) {
  bool any = false;
  for (const EstimateSeries& s : panel) {
    if (s.value_m.size() != s.t_s.size())
      bad_calibration("series '" + s.name + "' has " + std::to_string(s.t_s.size()) + " t_s values but " +
                      std::to_string(s.value_m.size()) + " value_m values");
    if (!s.sd_m.empty() && s.sd_m.size() != s.t_s.size())
      bad_calibration("series '" + s.name + "' has " + std::to_string(s.t_s.size()) + " t_s values but " +
                      std::to_string(s.sd_m.size()) + " sd_m values (expected the same or none)");
    for (std::size_t i = 0; i < s.t_s.size() && !any; ++i) any = finite_point(s, i);
  }
  if (!any) bad_calibration(std::string("the ") + which + " panel has no finite point");
}

void validate_calibration(const CalibrationFigureData& d) {
  if (d.radii.empty()) bad_calibration("no radius series");
  validate_panel(d.radii, "wheel radius");
  if (!d.wheel_base.empty()) validate_panel(d.wheel_base, "wheel base");
  for (std::size_t i = 0; i < d.markers.size(); ++i)
    if (!std::isfinite(d.markers[i].t_s))
      bad_calibration("markers[" + std::to_string(i) + "] time is not finite");
}

// "t v" rows; a blank line where a point is not finite (breaks the line).
std::string line_rows(const EstimateSeries& s) {
  std::string out;
  bool gap = false;
  for (std::size_t i = 0; i < s.t_s.size(); ++i) {
    if (!finite_point(s, i)) {
      if (!gap && !out.empty()) out += "\n";
      gap = true;
      continue;
    }
    gap = false;
    out += num_calibration(s.t_s[i]) + " " + num_calibration(s.value_m[i]) + "\n";
  }
  return out;
}

// "t lo hi" rows of the band value ± sd where all three are finite.
std::string band_rows(const EstimateSeries& s) {
  std::string out;
  for (std::size_t i = 0; i < s.sd_m.size(); ++i) {
    if (!finite_point(s, i) || !std::isfinite(s.sd_m[i])) continue;
    out += num_calibration(s.t_s[i]) + " " + num_calibration(s.value_m[i] - s.sd_m[i]) + " " +
           num_calibration(s.value_m[i] + s.sd_m[i]) + "\n";
  }
  return out;
}

// The plot command of one panel; appends its data files to `files` (named
// with `prefix`). `next_colour` counts the automatically coloured estimates
// over both panels (no two such lines share a colour, up to the palette's
// size); a caller that wants a method in one colour in both panels sets
// `colour`. Sets *any_band when a ±sd band is drawn.
std::string panel_plot(const std::vector<EstimateSeries>& panel, const std::string& prefix,
                       std::vector<std::pair<std::string, std::string>>& files, int* next_colour,
                       bool* any_band) {
  std::string bands, lines;
  for (std::size_t i = 0; i < panel.size(); ++i) {
    const EstimateSeries& s = panel[i];
    std::string colour;
    if (s.colour) {
      colour = kPalette[((*s.colour % kPaletteSize) + kPaletteSize) % kPaletteSize];
    } else if (s.truth) {
      colour = kTruthColour;
    } else {
      colour = kPalette[(*next_colour)++ % kPaletteSize];
    }
    const std::string base = prefix + std::to_string(i);
    std::string rows = line_rows(s);
    if (rows.empty()) continue;  // nothing finite in this series
    files.emplace_back(base + ".dat", std::move(rows));
    if (!s.sd_m.empty()) {
      std::string band = band_rows(s);
      if (!band.empty()) {
        files.emplace_back(base + "_band.dat", std::move(band));
        bands += (bands.empty() ? "" : ", \\\n     ") +
                 ("'" + base + "_band.dat' using 1:2:3 with filledcurves fc rgb '" + colour +
                  "' fs transparent solid 0.18 noborder notitle");
        *any_band = true;
      }
    }
    lines += (lines.empty() ? "" : ", \\\n     ") +
             ("'" + base + ".dat' using 1:2 with " + (s.truth ? "steps dt 2 lw 2" : "lines lw 1.8") +
              " lc rgb '" + colour + "' title " + q_calibration(s.name));
  }
  std::string plot = "plot ";
  if (!bands.empty()) plot += bands + ", \\\n     ";
  return plot + lines;
}

}  // namespace

void calibration_estimates_figure(const fs::path& stem, const CalibrationFigureData& d) {
  validate_calibration(d);
  double t_min = std::numeric_limits<double>::infinity(), t_max = -std::numeric_limits<double>::infinity();
  for (const auto* panel : {&d.radii, &d.wheel_base})
    for (const EstimateSeries& s : *panel)
      for (std::size_t i = 0; i < s.t_s.size(); ++i)
        if (finite_point(s, i)) t_min = std::min(t_min, s.t_s[i]), t_max = std::max(t_max, s.t_s[i]);
  if (t_max <= t_min) t_min -= 0.5, t_max += 0.5;

  const bool two_panels = !d.wheel_base.empty();
  std::vector<std::pair<std::string, std::string>> files;
  int next_colour = 0;
  bool any_band = false;
  const std::string top = panel_plot(d.radii, "r", files, &next_colour, &any_band);
  const std::string bottom = two_panels ? panel_plot(d.wheel_base, "d", files, &next_colour, &any_band) : "";

  std::string body;
  body += "set multiplot title " + q_calibration(d.title + (any_band ? " (shaded: estimate ± 1 sd)" : "")) +
          " font ',13'\n";
  body += "set grid lc rgb '#e0e0e0'\n";
  body += "set xrange [" + num_calibration(t_min) + ":" + num_calibration(t_max) + "]\n";
  body += "set key outside right top Left reverse\n";
  body += "set lmargin at screen 0.10\nset rmargin at screen 0.76\n";
  body += "set format y '%.4g'\n";
  body += "set offsets 0, 0, graph 0.05, graph 0.05\n";  // lines at the extremes stay off the border
  for (const auto& m : d.markers) {
    if (m.t_s < t_min || m.t_s > t_max) continue;
    body += "set arrow from first " + num_calibration(m.t_s) + ", graph 0 to first " + num_calibration(m.t_s) +
            ", graph 1 nohead back lw 1 dt 3 lc rgb '" + kMarkerColour + "'\n";
  }
  int tag = 1;
  for (const auto& m : d.markers) {
    if (m.t_s < t_min || m.t_s > t_max || m.label.empty()) continue;
    body += "set label " + std::to_string(tag++) + " " + q_calibration(m.label) + " at first " +
            num_calibration(m.t_s) + ", graph 1 left offset 0.4,-1 front tc rgb '#505050' font ',9'\n";
  }
  // Upper panel: the radii (x tic labels only on the lowest panel).
  body += "set tmargin at screen 0.91\n";
  body += std::string("set bmargin at screen ") + (two_panels ? "0.44" : "0.12") + "\n";
  body += "set ylabel 'wheel radius [m]'\n";
  if (two_panels) {
    body += "set format x ''\nunset xlabel\n";
  } else {
    body += "set xlabel " + q_calibration(d.time_label) + "\n";
  }
  body += top + "\n";
  if (two_panels) {
    body += "unset label\n";
    body += "set tmargin at screen 0.38\nset bmargin at screen 0.10\n";
    body += "set format x '%g'\nset xlabel " + q_calibration(d.time_label) + "\n";
    body += "set ylabel 'wheel base [m]'\n";
    body += bottom + "\n";
  }
  body += "unset multiplot\n";
  render_png_svg(stem, std::move(files), body, 1150, two_panels ? 820 : 560);
}

}  // namespace odotune::results

#include <odotune/jobs/calibration_figure_data.h>

#include <cmath>
#include <limits>

namespace odotune::jobs {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Rows to draw: every k-th row so that at most max_points remain, plus the
// last one.
std::vector<std::size_t> thinned_rows(std::size_t n, std::size_t max_points) {
  std::vector<std::size_t> rows;
  if (n == 0) return rows;
  const std::size_t cap = max_points < 3 ? 3 : max_points;
  // Rows 0, k, 2k, … ≤ n − 1 are ⌊(n−1)/k⌋ + 1 ≤ cap − 1, plus the last.
  const std::size_t step = n <= cap ? 1 : (n - 1 + cap - 3) / (cap - 2);
  for (std::size_t i = 0; i < n; i += step) rows.push_back(i);
  if (rows.back() != n - 1) rows.push_back(n - 1);
  return rows;
}

std::string named(const char* what, const std::string& label) {
  return label.empty() ? std::string(what) : std::string(what) + " " + label;
}

results::EstimateSeries series(const std::string& name, int colour, bool truth) {
  results::EstimateSeries s;
  s.name = name;
  s.colour = colour;
  s.truth = truth;
  return s;
}

}  // namespace

RunSeries estimate_series(const CalibrationTraceTable& table, const std::string& label, int first_colour,
                          bool with_sd, std::size_t max_points) {
  results::EstimateSeries rr = series(named("R_R", label), first_colour, false);
  results::EstimateSeries rl = series(named("R_L", label), first_colour + 1, false);
  results::EstimateSeries d = series(named("D", label), first_colour + 2, false);
  const auto add = [&](double t, const filters::OdometryParams& p, double sd_r, double sd_l, double sd_d) {
    rr.t_s.push_back(t), rl.t_s.push_back(t), d.t_s.push_back(t);
    rr.value_m.push_back(p.wheel_radius_right_m);
    rl.value_m.push_back(p.wheel_radius_left_m);
    d.value_m.push_back(p.wheel_base_m);
    if (with_sd) rr.sd_m.push_back(sd_r), rl.sd_m.push_back(sd_l), d.sd_m.push_back(sd_d);
  };
  if (!table.fixed_params.empty()) {
    // Constants: a flat line over each track (with the trace row's sds, if any).
    for (std::size_t k = 0; k < table.fixed_params.size(); ++k) {
      double sd[3] = {kNaN, kNaN, kNaN};
      for (std::size_t i = 0; i < table.track.size(); ++i)
        if (table.track[i] == static_cast<int>(k)) {
          const filters::CalibEstimate& e = table.estimate[i];
          sd[0] = e.sd_radius_right_m, sd[1] = e.sd_radius_left_m, sd[2] = e.sd_wheel_base_m;
          break;
        }
      add(table.track_start_elapsed_s[k], table.fixed_params[k], sd[0], sd[1], sd[2]);
      add(table.track_end_elapsed_s[k], table.fixed_params[k], sd[0], sd[1], sd[2]);
    }
  } else {
    for (std::size_t i : thinned_rows(table.t_s.size(), max_points)) {
      const filters::CalibEstimate& e = table.estimate[i];
      add(table.elapsed_s[i], e.params, e.sd_radius_right_m, e.sd_radius_left_m, e.sd_wheel_base_m);
    }
  }
  RunSeries out;
  out.radii = {std::move(rr), std::move(rl)};
  out.wheel_base = {std::move(d)};
  return out;
}

RunSeries truth_series(const CalibrationTraceTable& table, int first_colour) {
  RunSeries out;
  if (table.truth_pieces.empty()) return out;
  results::EstimateSeries rr = series("R_R true", first_colour, true);
  results::EstimateSeries rl = series("R_L true", first_colour + 1, true);
  results::EstimateSeries d = series("D true", first_colour + 2, true);
  const auto add = [&](double t, double r, double l, double b) {
    rr.t_s.push_back(t), rl.t_s.push_back(t), d.t_s.push_back(t);
    rr.value_m.push_back(r), rl.value_m.push_back(l), d.value_m.push_back(b);
  };
  for (std::size_t i = 0; i < table.truth_pieces.size(); ++i) {
    const auto& piece = table.truth_pieces[i];
    // A gap between tracks (a track without truth, or a new track).
    if (i > 0 && table.truth_pieces[i - 1].track != piece.track) add(piece.from_elapsed_s, kNaN, kNaN, kNaN);
    const filters::OdometryParams& p = piece.params;
    add(piece.from_elapsed_s, p.wheel_radius_right_m, p.wheel_radius_left_m, p.wheel_base_m);
    add(piece.to_elapsed_s, p.wheel_radius_right_m, p.wheel_radius_left_m, p.wheel_base_m);
  }
  out.radii = {std::move(rr), std::move(rl)};
  out.wheel_base = {std::move(d)};
  return out;
}

std::vector<results::CalibrationFigureData::Marker> run_markers(const CalibrationTraceTable& table) {
  std::vector<results::CalibrationFigureData::Marker> markers;
  for (std::size_t k = 1; k < table.track_names.size(); ++k)
    markers.push_back({table.track_start_elapsed_s[k], table.track_names[k]});
  for (double c : table.change_elapsed_s) markers.push_back({c, "radius step"});
  return markers;
}

results::CalibrationFigureData calibration_figure_data(const CalibrationTraceTable& table,
                                                       const std::string& title) {
  results::CalibrationFigureData d;
  d.title = title;
  d.time_label = table.track_names.size() > 1 ? "time since the calibration began (tracks end to end) [s]"
                                              : "time since the track's start [s]";
  RunSeries est = estimate_series(table, "", 0, true);
  RunSeries truth = truth_series(table, 0);
  d.radii = std::move(est.radii);
  d.wheel_base = std::move(est.wheel_base);
  for (auto& s : truth.radii) d.radii.push_back(std::move(s));
  for (auto& s : truth.wheel_base) d.wheel_base.push_back(std::move(s));
  d.markers = run_markers(table);
  return d;
}

}  // namespace odotune::jobs

#include <odotune/studies/study_outputs.h>

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/results/calibration_figures.h>
#include <odotune/results/gnuplot.h>

namespace odotune::studies {
namespace fs = std::filesystem;

namespace {

// At most this many points per line in the figures (the SVGs stay small).
constexpr std::size_t kMaxFigurePoints = 600;
// At most this many runs in a many-run figure (one palette colour each).
constexpr std::size_t kMaxFigureRuns = 10;

std::string runs_shown(std::size_t runs) {
  return runs > kMaxFigureRuns ? fmt::format("first {} of {} runs", kMaxFigureRuns, runs)
                               : fmt::format("{} runs", runs);
}

std::size_t decimation(std::size_t n) {
  return std::max<std::size_t>(1, (n + kMaxFigurePoints - 1) / kMaxFigurePoints);
}

// Every k-th point and the last one.
template <class T>
std::vector<double> thin(const std::vector<T>& v, std::size_t k) {
  std::vector<double> out;
  for (std::size_t i = 0; i < v.size(); i += k) out.push_back(static_cast<double>(v[i]));
  if (!v.empty() && (v.size() - 1) % k != 0) out.push_back(static_cast<double>(v.back()));
  return out;
}

// A piecewise-constant series reduced to its change points and last point
// (drawn with gnuplot `steps`, the same shape; long segments keep the dash
// pattern visible).
struct Steps {
  std::vector<double> t, v;
};
Steps change_points(const std::vector<double>& t, const std::vector<double>& v) {
  Steps out;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (i == 0 || i + 1 == t.size() || v[i] != v[i - 1]) {
      out.t.push_back(t[i]);
      out.v.push_back(v[i]);
    }
  return out;
}

void write_text(const fs::path& p, std::string_view what, const std::string& text,
                std::vector<fs::path>* files) {
  core::write_atomically(p, what, text);
  files->push_back(p);
}

// Normalises mean and sd of every cell by the largest finite mean.
void normalise(results::BarPanel* p) {
  double top = 0.0;
  for (const auto& row : p->mean)
    for (double v : row)
      if (std::isfinite(v)) top = std::max(top, v);
  if (top <= 0.0) return;
  for (auto& row : p->mean)
    for (double& v : row) v /= top;
  for (auto& row : p->sd)
    for (double& v : row) v /= top;
}

// Fig. 6a/6b analogue: one panel per wheel, every run's estimate (colour =
// run) with its truth dashed in the same colour.
std::vector<results::TimePanel> radius_panels(const std::vector<ParamTrace>& traces) {
  results::TimePanel right{"R_R [m]", {}}, left{"R_L [m]", {}};
  for (std::size_t r = 0; r < std::min(traces.size(), kMaxFigureRuns); ++r) {
    const ParamTrace& t = traces[r];
    const std::size_t k = decimation(t.t_s.size());
    const auto ts = thin(t.t_s, k);
    const int colour = static_cast<int>(r);
    const Steps true_right = change_points(t.t_s, t.true_r_right_m),
                true_left = change_points(t.t_s, t.true_r_left_m);
    right.lines.push_back({fmt::format("run {}", r), ts, thin(t.r_right_m, k), colour, false, true});
    right.lines.push_back({r == 0 ? "truth (dashed)" : "", true_right.t, true_right.v, colour, true, false});
    left.lines.push_back({"", ts, thin(t.r_left_m, k), colour, false, true});
    left.lines.push_back({"", true_left.t, true_left.v, colour, true, false});
  }
  return {right, left};
}

results::TimePanel particle_panel(const std::string& label, const std::vector<ParamTrace>& traces) {
  results::TimePanel p{label, {}};
  for (std::size_t r = 0; r < std::min(traces.size(), kMaxFigureRuns); ++r) {
    const std::size_t k = decimation(traces[r].t_s.size());
    p.lines.push_back({fmt::format("run {}", r), thin(traces[r].t_s, k), thin(traces[r].particles, k),
                       static_cast<int>(r), false, true});
  }
  return p;
}

std::vector<results::TimeMarker> step_markers(const CalibrationStudy& s) {
  if (!std::isfinite(s.step_time_s)) return {};
  return {{s.step_time_s, "radius step"}};
}

// Fig. 8 analogue: one run, adaptive PF vs DKF, with the truth.
results::CalibrationFigureData dkf_vs_pf(const ParamTrace& pf, const ParamTrace& dkf,
                                         const std::string& title) {
  results::CalibrationFigureData d;
  d.title = title;
  const auto series = [](const std::string& name, const ParamTrace& t, const std::vector<double>& v,
                         std::optional<int> colour, bool truth) {
    const std::size_t k = decimation(t.t_s.size());
    results::EstimateSeries s;
    s.name = name;
    if (truth) {
      Steps st = change_points(t.t_s, v);
      s.t_s = std::move(st.t);
      s.value_m = std::move(st.v);
    } else {
      s.t_s = thin(t.t_s, k);
      s.value_m = thin(v, k);
    }
    s.truth = truth;
    s.colour = colour;
    return s;
  };
  d.radii = {series("R_R adaptive-pf", pf, pf.r_right_m, 0, false),
             series("R_L adaptive-pf", pf, pf.r_left_m, 5, false),
             series("R_R dkf", dkf, dkf.r_right_m, 1, false),
             series("R_L dkf", dkf, dkf.r_left_m, 4, false),
             series("R_R true", pf, pf.true_r_right_m, std::nullopt, true),
             series("R_L true", pf, pf.true_r_left_m, std::nullopt, true)};
  d.wheel_base = {series("D adaptive-pf", pf, pf.wheel_base_m, 0, false),
                  series("D dkf", dkf, dkf.wheel_base_m, 1, false),
                  series("D true", pf, pf.true_wheel_base_m, std::nullopt, true)};
  return d;
}

}  // namespace

ResamplingBars resampling_bars(const ResamplingStudy& s) {
  ResamplingBars b;
  const auto resamplers = table1_resamplers();
  const auto policies = table1_policies();
  for (auto r : resamplers) b.groups.emplace_back(filters::to_string(r));
  for (auto p : policies) b.series.emplace_back(filters::to_string(p));
  results::BarPanel err{"radius error, normalised [-]", {}, {}},
      time{"time per iteration, normalised [-]", {}, {}};
  for (auto* p : {&err, &time}) {
    p->mean.assign(resamplers.size(), std::vector<double>(policies.size(), NAN));
    p->sd = p->mean;
  }
  for (const ResamplingCell& c : s.cells) {
    const auto g = static_cast<std::size_t>(std::find(resamplers.begin(), resamplers.end(), c.resampler) -
                                            resamplers.begin());
    const auto k = static_cast<std::size_t>(std::find(policies.begin(), policies.end(), c.policy) -
                                            policies.begin());
    if (g >= resamplers.size() || k >= policies.size()) continue;
    std::vector<double> e;
    for (const ResamplingRunResult& r : c.runs) e.push_back(0.5 * (r.err_rr_m + r.err_rl_m));
    const MeanSd m = mean_sd(e);
    err.mean[g][k] = m.mean;
    err.sd[g][k] = m.sd;
    time.mean[g][k] = c.ms_per_iteration.mean;
    time.sd[g][k] = c.ms_per_iteration.sd;
  }
  normalise(&err);
  normalise(&time);
  b.panels = {err, time};
  return b;
}

std::vector<fs::path> write_resampling_outputs(const ResamplingStudy& s, const StudyContext& c,
                                               const fs::path& dir) {
  std::vector<fs::path> files;
  write_text(dir / "table1.csv", "table", table1_csv(s), &files);
  write_text(dir / "table1_runs.csv", "table", table1_runs_csv(s), &files);
  write_text(dir / "table1.md", "table", table1_markdown(s, c), &files);
  const ResamplingBars bars = resampling_bars(s);
  const fs::path stem = dir / "fig3_4_resampling";
  results::grouped_bars(stem,
                        fmt::format("Resampling (Fig. 3/4 analogue), {} runs, N = {}: mean ± sd / largest mean",
                                    s.options.runs, s.options.pf_particles),
                        bars.groups, bars.series, bars.panels);
  results::append_png_svg(stem, &files);
  return files;
}

std::vector<fs::path> write_calibration_outputs(const CalibrationStudy& s, const StudyContext& c,
                                                const fs::path& dir) {
  std::vector<fs::path> files;
  write_text(dir / "table2.csv", "table", table2_csv(s), &files);
  write_text(dir / "table2_runs.csv", "table", table2_runs_csv(s), &files);
  write_text(dir / "table2.md", "table", table2_markdown(s, c), &files);
  const auto markers = step_markers(s);
  const std::string runs = runs_shown(static_cast<std::size_t>(s.options.runs));

  fs::path stem = dir / "fig5_particles";
  results::time_panels(stem, fmt::format("Adaptive-PF particle count over time, {} (Fig. 5 analogue)", runs),
                       {particle_panel("N, step track [-]", s.pf_step),
                        particle_panel("N, constant track [-]", s.pf_constant)},
                       markers);
  results::append_png_svg(stem, &files);
  stem = dir / "fig6a_radii_constant";
  results::time_panels(stem,
                       fmt::format("Adaptive-PF radii, {} with random true radii (Fig. 6a analogue)", runs),
                       radius_panels(s.pf_constant), {});
  results::append_png_svg(stem, &files);
  stem = dir / "fig6b_radii_step";
  results::time_panels(stem,
                       fmt::format("Adaptive-PF radii under changing conditions, {} (Fig. 6b analogue)", runs),
                       radius_panels(s.pf_step), markers);
  results::append_png_svg(stem, &files);
  for (const bool step : {true, false}) {
    const auto& pf = step ? s.pf_step : s.pf_constant;
    const auto& dkf = step ? s.dkf_step : s.dkf_constant;
    if (pf.empty() || dkf.empty()) continue;
    stem = dir / (step ? "fig8_dkf_vs_pf_step" : "fig8_dkf_vs_pf_constant");
    results::CalibrationFigureData d = dkf_vs_pf(
        pf.front(), dkf.front(),
        fmt::format("DKF vs adaptive PF, {} track, run 0 (Fig. 8 analogue)", step ? "step" : "constant"));
    if (step && std::isfinite(s.step_time_s)) d.markers.push_back({s.step_time_s, "radius step"});
    results::calibration_estimates_figure(stem, d);
    results::append_png_svg(stem, &files);
  }
  return files;
}

}  // namespace odotune::studies

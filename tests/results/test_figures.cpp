// Figures: each figure renders a PNG and an SVG through gnuplot. gnuplot is a
// build dependency (scripts/install-deps.sh installs gnuplot-nox): when it is
// missing these tests FAIL on purpose.
#include <odotune/results/figures.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>

#include <odotune/results/gnuplot.h>
#include <odotune/results/param_range_figure.h>

#include "support/cli_runner.h"

namespace odotune::results {
namespace {
namespace fs = std::filesystem;

using testing_support::slurp;

class FiguresTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(gnuplot_available()) << "gnuplot is required (Debian gnuplot-nox, see scripts/install-deps.sh)";
    std::string tmpl = (fs::temp_directory_path() / "odotune-figtest-XXXXXX").string();
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }

  // Checks STEM.png and STEM.svg; returns the SVG text.
  std::string expect_outputs(const std::string& stem) {
    const fs::path png = dir_ / (stem + ".png"), svg = dir_ / (stem + ".svg");
    EXPECT_TRUE(fs::exists(png)) << png;
    EXPECT_TRUE(fs::exists(svg)) << svg;
    const std::string png_bytes = slurp(png);
    EXPECT_GT(png_bytes.size(), 1024u);
    EXPECT_EQ(png_bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    const std::string s = slurp(svg);
    EXPECT_NE(s.find("<svg"), std::string::npos);
    EXPECT_NE(s.find("</svg>"), std::string::npos);
    // Nothing but the two outputs is left in the directory (no .tmp files).
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir_)) {
      EXPECT_EQ(e.path().extension() == ".png" || e.path().extension() == ".svg", true) << e.path();
      ++n;
    }
    EXPECT_EQ(n % 2, 0);
    return s;
  }

  static void expect_contains(const std::string& svg, const std::string& text) {
    EXPECT_NE(svg.find(text), std::string::npos) << "SVG lacks \"" << text << "\"";
  }

  fs::path dir_;
};

std::vector<std::vector<double>> heat_values(std::size_t ncols) {
  std::vector<std::vector<double>> v(7, std::vector<double>(ncols));
  for (std::size_t r = 0; r < 7; ++r) {
    for (std::size_t c = 0; c < ncols; ++c) {
      v[r][c] = -20.0 + 7.3 * static_cast<double>(r) + 3.1 * static_cast<double>(c);
    }
  }
  return v;
}

TEST_F(FiguresTest, HeatmapRendersTitleLabelsTracksAndCellValues) {
  const std::vector<std::string> tracks = {"square_cw", "figure8", "corridor"};
  auto v = heat_values(tracks.size());
  v[0][0] = 12.34;                                     // printed as 12.3
  v[6][2] = -5.06;                                     // printed as -5.1
  v[3][1] = std::numeric_limits<double>::quiet_NaN();  // missing cell
  v[2][2] = -0.01;                                     // printed as 0.0, not -0.0
  heatmap(dir_ / "heat", "RMSE improvement (%) — rq model", tracks, v);
  const std::string svg = expect_outputs("heat");
  expect_contains(svg, "RMSE improvement (%) — rq model");
  expect_contains(svg, "improvement [%]");
  expect_contains(svg, "fitness mode");
  expect_contains(svg, ">track<");
  for (const auto& t : tracks) expect_contains(svg, t);  // underscores verbatim
  expect_contains(svg, "1 RMSE");
  expect_contains(svg, "7 RMSE+MAE+MAXE");
  expect_contains(svg, "12.3");
  expect_contains(svg, "-5.1");
  expect_contains(svg, "n/a");
  EXPECT_EQ(svg.find("-0.0<"), std::string::npos);
  // A cell value not in the matrix must not show up: e.g. the NaN cell's
  // would-be value -20 + 7.3*3 + 3.1 = 5.0.
  EXPECT_EQ(svg.find(">5.0<"), std::string::npos);
}

TEST_F(FiguresTest, HeatmapAllMissingStillRenders) {
  std::vector<std::vector<double>> v(7, std::vector<double>(2, std::numeric_limits<double>::quiet_NaN()));
  heatmap(dir_ / "empty", "all missing", {"a", "b"}, v);
  const std::string svg = expect_outputs("empty");
  expect_contains(svg, "all missing");
  expect_contains(svg, "n/a");
}

TEST_F(FiguresTest, HeatmapRejectsWrongShape) {
  EXPECT_THROW(heatmap(dir_ / "x", "t", {"a", "b"}, heat_values(3)), std::invalid_argument);
  EXPECT_THROW(heatmap(dir_ / "x", "t", {"a"}, std::vector<std::vector<double>>(6, {1.0})),
               std::invalid_argument);
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(FiguresTest, TitlesWithQuotesAndBackslashesAreVerbatim) {
  const std::string title = "it's a \"test\" of a\\b and x_1^2";
  heatmap(dir_ / "q", title, {"o'brien"}, std::vector<std::vector<double>>(7, {1.0}));
  const std::string svg = expect_outputs("q");
  // gnuplot's SVG escapes XML specials; the apostrophe, backslash, `_` and
  // `^` appear as written (noenhanced).
  expect_contains(svg, "it's a");
  expect_contains(svg, "a\\b and x_1^2");
  expect_contains(svg, "o'brien");
}

TEST_F(FiguresTest, MissingOutputDirectoryThrowsAndLeavesNothing) {
  const fs::path missing = dir_ / "no" / "such" / "dir";
  try {
    heatmap(missing / "heat", "t", {"a"}, std::vector<std::vector<double>>(7, {1.0}));
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("output directory does not exist"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "no"));
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(FiguresTest, GnuplotErrorIsReportedAndLeavesNothing) {
  GnuplotJob job;
  job.script = "set terminal svg\nset output 'a.svg'\nplot undefined_function_xyz(x)\n";
  job.outputs = {{"a.svg", dir_ / "a.svg"}};
  try {
    run_gnuplot(job);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("gnuplot failed"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(FiguresTest, MissingGnuplotIsAPlainError) {
  const char* old = std::getenv("PATH");
  const std::string saved = old ? old : "";
  ASSERT_EQ(::setenv("PATH", (dir_ / "empty-path").c_str(), 1), 0);
  bool threw = false;
  try {
    heatmap(dir_ / "h", "t", {"a"}, std::vector<std::vector<double>>(7, {1.0}));
  } catch (const std::runtime_error& e) {
    threw = true;
    EXPECT_NE(std::string(e.what()).find("gnuplot is not installed"), std::string::npos) << e.what();
  }
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_TRUE(threw);
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(FiguresTest, OverwritesExistingOutputs) {
  { std::ofstream(dir_ / "h.png") << "old"; }
  { std::ofstream(dir_ / "h.svg") << "old"; }
  heatmap(dir_ / "h", "fresh", {"a"}, std::vector<std::vector<double>>(7, {1.0}));
  expect_contains(expect_outputs("h"), "fresh");
}

TEST_F(FiguresTest, BoxplotsRenderModelsMetricsAndLegend) {
  std::mt19937 rng(42);
  std::normal_distribution<double> noise(10.0, 8.0);
  std::map<std::string, std::map<std::string, std::vector<double>>> data;
  for (const char* model : {"rq", "alpha", "gyro"}) {
    for (const char* metric : {"RMSE", "MAE", "MAXE"}) {
      auto& v = data[model][metric];
      for (int i = 0; i < 20; ++i) v.push_back(noise(rng));
    }
  }
  data["gyro"]["MAXE"].push_back(std::numeric_limits<double>::quiet_NaN());  // ignored
  data["rq"]["MAE"].clear();                                                 // no box
  boxplots(dir_ / "box", "Improvement per model", data);
  const std::string svg = expect_outputs("box");
  expect_contains(svg, "Improvement per model");
  expect_contains(svg, "improvement [%]");
  expect_contains(svg, ">model<");
  for (const char* s : {"rq", "alpha", "gyro", "RMSE", "MAE", "MAXE"}) expect_contains(svg, s);
  EXPECT_THROW(boxplots(dir_ / "b2", "t", {{"rq", {{"RMSE", {std::numeric_limits<double>::quiet_NaN()}}}}}),
               std::invalid_argument);
}

// How many filled circles (gnuplot point type 7) of colour `rgb` ("r, g, b")
// an SVG draws: the plotted points, plus one per legend sample of that colour.
std::size_t svg_points(const std::string& svg, int r, int g, int b) {
  char colour[64];
  std::snprintf(colour, sizeof colour, "color='rgb(%3d, %3d, %3d)'", r, g, b);
  std::size_t n = 0;
  for (auto p = svg.find("<use xlink:href='#gpPt6' transform="); p != std::string::npos;
       p = svg.find("<use xlink:href='#gpPt6' transform=", p + 1))
    if (svg.compare(svg.find("color=", p), std::strlen(colour), colour) == 0) ++n;
  return n;
}

// One run per box (a one-seed rl-ekf experiment: two fitnesses, three
// metrics, every improvement negative): each value is drawn, and inside the
// y range (gnuplot leaves out points outside it).
TEST_F(FiguresTest, BoxplotsDrawEveryValueOfBoxesOfOneToThreeRuns) {
  std::map<std::string, std::map<std::string, std::vector<double>>> data;
  data["outage"] = {{"RMSE", {-176.3}}, {"MAE", {-150.2}}, {"MAXE", {-120.9}}};
  data["both"] = {{"RMSE", {-190.8, -185.0, -60.0}}, {"MAE", {-170.0, -10.0}}, {"MAXE", {-140.0}}};
  boxplots(dir_ / "small", "Held-out improvement", data, {"fitness", false});
  const std::string svg = expect_outputs("small");
  expect_contains(svg, ">fitness<");
  EXPECT_EQ(svg_points(svg, 0, 114, 178), 1u + 3u);  // RMSE
  EXPECT_EQ(svg_points(svg, 230, 159, 0), 1u + 2u);  // MAE
  EXPECT_EQ(svg_points(svg, 0, 158, 115), 1u + 1u);  // MAXE
  // The y axis holds the data: a tic at or below -190.8 is labelled (the
  // defect drew an axis of -1…1).
  expect_contains(svg, ">-200<");
  EXPECT_EQ(svg.find(">-1<"), std::string::npos);
}

TEST_F(FiguresTest, BoxplotsWithPointsDrawOnePointPerValueOverTheBoxes) {
  std::map<std::string, std::map<std::string, std::vector<double>>> data;
  for (int i = 0; i < 6; ++i) {
    data["outage"]["RMSE"].push_back(10.0 + i);
    data["both"]["RMSE"].push_back(-5.0 * i);
  }
  data["both"]["RMSE"].push_back(std::numeric_limits<double>::quiet_NaN());  // not drawn
  boxplots(dir_ / "pts", "t", data, {"fitness", true});
  EXPECT_EQ(svg_points(expect_outputs("pts"), 0, 114, 178), 12u);
  // Without points, boxes of 4 or more values draw only their outliers (none here).
  boxplots(dir_ / "nopts", "t", data);
  const std::string svg = expect_outputs("nopts");
  EXPECT_EQ(svg_points(svg, 0, 114, 178), 0u);
  expect_contains(svg, ">model<");
}

TEST_F(FiguresTest, ParamRangesDrawABarPerSeedADotPerValueAndTheReference) {
  const std::vector<std::string> params = {"q_x", "q_yaw", "q_vx"};
  std::vector<ParamRangeSeries> series = {
      {"seed 1", {2.0, 1.0, 0.05}, {{1.5, 3.0, true}, {0.01, 100.0, false}, {0.02, 0.2, true}}},
      {"seed 2", {2.5, 1.0, 0.04}, {{1.2, 4.0, true}, {0.0, HUGE_VAL, false}, {0.01, 0.1, true}}},
  };
  param_ranges_figure(dir_ / "ranges", "test1, fitness outage: tuned factors", "factor (log scale)", params,
                      series, 1.0, "the file's value (factor 1)");
  const std::string svg = expect_outputs("ranges");
  for (const char* s : {"test1, fitness outage: tuned factors", "factor (log scale)", "q_x", "q_yaw", "q_vx",
                        "seed 1", "seed 2", "the file's value (factor 1)", "tuned value", "not determined"})
    expect_contains(svg, s);
  EXPECT_EQ(svg_points(svg, 0, 0, 0), 6u + 1u);  // every tuned value, and the legend's sample
  series[1].ranges.pop_back();
  EXPECT_THROW(param_ranges_figure(dir_ / "r2", "t", "x", params, series, 1.0, "ref"), std::invalid_argument);
  EXPECT_THROW(param_ranges_figure(dir_ / "r3", "t", "x", {}, {}, 1.0, "ref"), std::invalid_argument);
}

TEST(FiguresResample, StepWiseOntoUnionGrid) {
  // Run A: 10 → 5.0, 30 → 3.0; run B: 20 → 4.0, 40 → 1.0.
  const std::vector<std::vector<ConvergencePoint>> runs = {
      {{30, 3.0}, {10, 5.0}},  // unsorted on purpose
      {{20, 4.0}, {40, 1.0}},
      {},
  };
  const ConvergenceBand b = resample_convergence(runs);
  ASSERT_EQ(b.evaluations, (std::vector<long>{10, 20, 30, 40}));
  EXPECT_EQ(b.runs, (std::vector<int>{1, 2, 2, 2}));
  EXPECT_DOUBLE_EQ(b.median_m[0], 5.0);
  EXPECT_DOUBLE_EQ(b.median_m[1], 4.5);  // (5 + 4) / 2
  EXPECT_DOUBLE_EQ(b.min_m[2], 3.0);
  EXPECT_DOUBLE_EQ(b.max_m[2], 4.0);
  EXPECT_DOUBLE_EQ(b.min_m[3], 1.0);  // A holds 3.0 after its last point
  EXPECT_DOUBLE_EQ(b.max_m[3], 3.0);
  EXPECT_TRUE(resample_convergence({}).evaluations.empty());
}

TEST_F(FiguresTest, ConvergenceRendersSeriesAndBandLegend) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> step(15, 40);
  std::map<std::string, std::vector<std::vector<ConvergencePoint>>> series;
  for (const char* name : {"pso_rq", "nm_alpha"}) {
    for (int seed = 0; seed < 5; ++seed) {
      std::vector<ConvergencePoint> run;
      double best = 2.0 + 0.1 * seed;
      for (long e = step(rng); e < 600; e += step(rng)) {
        best *= 0.97;
        run.push_back({e, best});
      }
      series[name].push_back(run);
    }
  }
  convergence(dir_ / "conv", "Convergence of the solvers", series);
  const std::string svg = expect_outputs("conv");
  expect_contains(svg, "Convergence of the solvers");
  expect_contains(svg, "evaluations");
  expect_contains(svg, "best fitness [m]");
  expect_contains(svg, "pso_rq median");
  expect_contains(svg, "nm_alpha min–max (5 runs)");
  EXPECT_THROW(convergence(dir_ / "c2", "t", {{"x", {{}}}}), std::invalid_argument);
}

TEST_F(FiguresTest, TrajectoriesRenderWithLegendAndGaps) {
  std::vector<TrajectoryPath> paths(3);
  paths[0].name = "ground truth";
  paths[1].name = "baseline EKF";
  paths[2].name = "tuned rq";
  for (int i = 0; i <= 200; ++i) {
    const double t = 2.0 * M_PI * i / 200.0;
    paths[0].xs_m.push_back(5.0 * std::cos(t));
    paths[0].ys_m.push_back(3.0 * std::sin(t));
    paths[1].xs_m.push_back(5.4 * std::cos(t) + 0.002 * i);
    paths[1].ys_m.push_back(3.3 * std::sin(t));
    paths[2].xs_m.push_back(5.1 * std::cos(t));
    paths[2].ys_m.push_back(i == 50 ? std::numeric_limits<double>::quiet_NaN() : 3.05 * std::sin(t));
  }
  trajectories(dir_ / "traj", "Trajectories on track_a", paths);
  const std::string svg = expect_outputs("traj");
  expect_contains(svg, "Trajectories on track_a");
  expect_contains(svg, "x [m]");
  expect_contains(svg, "y [m]");
  for (const auto& p : paths) expect_contains(svg, p.name);

  paths[1].ys_m.pop_back();
  EXPECT_THROW(trajectories(dir_ / "t2", "t", paths), std::invalid_argument);
  EXPECT_THROW(trajectories(dir_ / "t3", "t", {}), std::invalid_argument);
}

// A path's points in SVG pixels: the coordinates of the SVG path drawn in
// `stroke`, after its legend sample (the first two points).
std::vector<std::pair<double, double>> svg_path_points(const std::string& svg, const std::string& stroke) {
  const auto at = svg.find("<path stroke='" + stroke + "'  d='M", svg.find("</defs>"));
  EXPECT_NE(at, std::string::npos) << stroke;
  std::vector<std::pair<double, double>> out;
  if (at == std::string::npos) return out;
  const std::string d = svg.substr(at, svg.find("'/>", at) - at);
  static const std::regex xy(R"(([0-9.]+),([0-9.]+))");
  for (auto it = std::sregex_iterator(d.begin(), d.end(), xy); it != std::sregex_iterator(); ++it)
    out.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  out.erase(out.begin(), out.begin() + std::min<std::ptrdiff_t>(2, static_cast<std::ptrdiff_t>(out.size())));
  return out;
}

// The plot border's size in SVG pixels: the largest closed black rectangle.
std::pair<double, double> svg_plot_size(const std::string& svg) {
  static const std::regex rect(
      R"(d='M([0-9.]+),([0-9.]+) L([0-9.]+),([0-9.]+) L([0-9.]+),([0-9.]+) L([0-9.]+),([0-9.]+) L[0-9.]+,[0-9.]+ Z)");
  std::pair<double, double> best{0, 0};
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), rect); it != std::sregex_iterator(); ++it) {
    double w = 0, h = 0;
    for (int k = 1; k <= 6; k += 2) {
      w = std::max(w, std::abs(std::stod((*it)[k + 2]) - std::stod((*it)[k])));
      h = std::max(h, std::abs(std::stod((*it)[k + 3]) - std::stod((*it)[k + 1])));
    }
    if (w * h > best.first * best.second) best = {w, h};
  }
  return best;
}

// A wide and a tall path: x and y at the same scale, and the plot area
// fitted to the data (no blank band around a path, as a 1000 × 750 canvas
// left around a 145 m × 30 m bag).
TEST_F(FiguresTest, TrajectoriesAreAtEqualScaleAndFillThePlot) {
  for (const auto& [sx_m, sy_m] : {std::pair{145.0, 30.0}, std::pair{12.0, 60.0}, std::pair{40.0, 40.0}}) {
    TrajectoryPath p{"path", {}, {}};
    for (int i = 0; i <= 100; ++i) {
      const double t = i / 100.0;
      p.xs_m.push_back(-20.0 + sx_m * t);
      p.ys_m.push_back(5.0 + sy_m * (0.5 - 0.5 * std::cos(2.0 * M_PI * t)));
    }
    const std::string stem = "fit" + std::to_string(static_cast<int>(sx_m));
    trajectories(dir_ / stem, "a title of sixty characters or so, as the reports' titles", {p});
    const std::string svg = expect_outputs(stem);
    const auto pts = svg_path_points(svg, "rgb(  0,   0,   0)");
    ASSERT_EQ(pts.size(), 101u) << stem;
    double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
    for (const auto& [x, y] : pts) {
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
    const double px_per_m_x = (x1 - x0) / sx_m, px_per_m_y = (y1 - y0) / sy_m;
    EXPECT_NEAR(px_per_m_x / px_per_m_y, 1.0, 0.02) << stem;
    const auto [w, h] = svg_plot_size(svg);
    // The canvas holds the plot, its labels and the legend, and no blank band:
    // 1000 × 750 around a 608 × 131 plot before.
    std::smatch size;
    ASSERT_TRUE(std::regex_search(svg, size, std::regex(R"re(width="([0-9]+)" height="([0-9]+)")re")));
    EXPECT_LE(std::stod(size[1]) - w, 250.0) << stem << ": plot " << w << " wide on a canvas of " << size[1];
    EXPECT_LE(std::stod(size[2]) - h, 130.0) << stem << ": plot " << h << " high on a canvas of " << size[2];
    // The data span the plot in its longer direction, within the 3 % margins.
    EXPECT_GT(std::max((x1 - x0) / w, (y1 - y0) / h), 0.9)
        << stem << ": " << x1 - x0 << " of " << w << ", " << y1 - y0 << " of " << h;
    EXPECT_LE((x1 - x0) / w, 1.0) << stem;
    EXPECT_LE((y1 - y0) / h, 1.0) << stem;
  }
}

}  // namespace
}  // namespace odotune::results

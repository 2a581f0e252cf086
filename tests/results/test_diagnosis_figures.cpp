// Figures and HTML page of `odotune diagnose --report`. gnuplot is a build
// dependency (scripts/install-deps.sh): when it is missing these tests FAIL
// on purpose, as the study's figure tests do.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

#include <odotune/results/diagnosis_figures.h>
#include <odotune/results/diagnosis_report.h>
#include <odotune/results/gnuplot.h>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace odotune::results {
namespace {
namespace fs = std::filesystem;
using testing_support::TempDir;

const std::string kFinding = "lateral_skid k = 0.021 ± 0.002";

using testing_support::slurp;

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

// A robot driving a circle of radius 5 m for 60 s (10 Hz); the window replay
// is re-anchored every 5 s; its error grows fast inside two segments
// ([10, 20] s and [35, 45] s) and slowly elsewhere; the finding removes most
// of it. The condition block has 6000 rows (more than the scatter shows):
// the residual rises with the condition before and is flat after; two far
// outliers.
DiagnosisFigureData synthetic(bool with_finding) {
  DiagnosisFigureData d;
  d.track = "circle_cw";
  d.finding = with_finding ? kFinding : "";
  std::mt19937 rng(1234);
  std::normal_distribution<double> noise(0.0, 0.002);
  const int n = 601;
  for (int i = 0; i < n; ++i) {
    const double t = i / 10.0;
    const double since_anchor = std::fmod(t, 5.0);
    const bool in_segment = (t >= 10 && t <= 20) || (t >= 35 && t <= 45);
    const double err = (in_segment ? 0.08 : 0.01) * since_anchor + std::abs(noise(rng));
    d.t_s.push_back(t);
    d.before_pos_err_m.push_back(err);
    if (with_finding) d.after_pos_err_m.push_back(0.2 * err);
    const double a = 2.0 * M_PI * t / 60.0;
    d.ref_x_m.push_back(5.0 * std::cos(a));
    d.ref_y_m.push_back(-5.0 * std::sin(a));
    d.flagged.push_back(in_segment ? 1 : 0);
  }
  d.before_pos_err_m[300] = std::numeric_limits<double>::quiet_NaN();  // a gap in the line
  d.segments = {{10.0, 20.0}, {35.0, 45.0}};
  for (double w = 0; w < 60; w += 5) d.window_starts_s.push_back(w);

  d.condition_label = "|v*w| [m/s^2]";
  d.residual_label = "lateral error growth [m/s]";
  std::uniform_real_distribution<double> cond(0.0, 0.6);
  for (int i = 0; i < 6000; ++i) {
    const double c = cond(rng);
    d.condition_value.push_back(c);
    d.before_residual.push_back(0.05 * c + noise(rng));
    if (with_finding) d.after_residual.push_back(noise(rng));
  }
  d.before_residual[17] = std::numeric_limits<double>::quiet_NaN();  // skipped row
  d.before_residual[100] = 4.0;  // two far outliers: the y axis shows the quantiles
  d.before_residual[200] = -3.0;

  // The boxes around the two segments' arcs (angles 60–120° and 210–270°).
  d.regions = {{-2.8, 2.8, -5.3, -4.0}, {-5.3, 0.2, 2.2, 5.3}};

  TrajectoryPath ref{"reference", d.ref_x_m, d.ref_y_m};
  TrajectoryPath nominal{"nominal replay", {}, {}}, corrected{"corrected replay", {}, {}};
  for (int i = 0; i < n; ++i) {
    nominal.xs_m.push_back(1.06 * d.ref_x_m[i]);
    nominal.ys_m.push_back(1.06 * d.ref_y_m[i]);
    corrected.xs_m.push_back(1.01 * d.ref_x_m[i]);
    corrected.ys_m.push_back(1.01 * d.ref_y_m[i]);
  }
  d.overlay = {ref, nominal};
  if (with_finding) d.overlay.push_back(corrected);
  return d;
}

// Checks STEM.png (signature) and STEM.svg; returns the SVG text.
std::string expect_figure(const fs::path& stem) {
  const std::string png = slurp(fs::path(stem) += ".png");
  EXPECT_GT(png.size(), 1024u) << stem;
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << stem;
  const std::string svg = slurp(fs::path(stem) += ".svg");
  EXPECT_NE(svg.find("<svg"), std::string::npos) << stem;
  EXPECT_NE(svg.find("</svg>"), std::string::npos) << stem;
  return svg;
}

void expect_contains(const std::string& text, const std::string& what, const std::string& where) {
  EXPECT_NE(text.find(what), std::string::npos) << where << " lacks \"" << what << "\"";
}

// Restores PATH when it goes (tests simulate a missing gnuplot).
class PathOverride {
 public:
  explicit PathOverride(const std::string& path) {
    const char* old = std::getenv("PATH");
    saved_ = old ? old : "";
    ::setenv("PATH", path.c_str(), 1);
  }
  ~PathOverride() { ::setenv("PATH", saved_.c_str(), 1); }
  PathOverride(const PathOverride&) = delete;
  PathOverride& operator=(const PathOverride&) = delete;

 private:
  std::string saved_;
};

class DiagnosisFiguresTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(gnuplot_available()) << "gnuplot is required (Debian gnuplot-nox, see scripts/install-deps.sh)";
  }
  TempDir dir_{"diagfig"};
};

TEST_F(DiagnosisFiguresTest, WritesEveryFigureWithTitlesLabelsAndLegends) {
  const DiagnosisFigureData d = synthetic(true);
  const auto stems = diagnosis_figures(dir_.path(), d);
  ASSERT_EQ(stems, (std::vector<fs::path>{dir_ / "residual_time", dir_ / "residual_condition", dir_ / "map",
                                          dir_ / "overlay"}));
  EXPECT_EQ(dir_.entries(), 8u);  // 4 × (png, svg), nothing else

  const std::string time = expect_figure(stems[0]);
  for (const std::string& s :
       std::vector<std::string>{"circle_cw", "time [s]", "position error [m]", "before: nominal model",
                                "after: " + kFinding, "located segment", "window start"})
    expect_contains(time, s, "residual_time.svg");

  const std::string cond = expect_figure(stems[1]);
  for (const std::string& s : std::vector<std::string>{
           "circle_cw", "|v*w| [m/s^2]", "lateral error growth [m/s]", "before: nominal model",
           "after: " + kFinding, "median in 15 quantile bins", "(y axis: 0.5–99.5 % quantiles)",
           // 5999 finite before rows → every 2nd shown.
           "5999 rows (1 in 2 shown)", "6000 rows (1 in 2 shown)"})
    expect_contains(cond, s, "residual_condition.svg");

  const std::string map = expect_figure(stems[2]);
  for (const std::string& s :
       std::vector<std::string>{"circle_cw", "x [m]", "y [m]", "reference path", "region 1", "region 2",
                                "located region", "residual above noise (202 samples)"})
    expect_contains(map, s, "map.svg");
  EXPECT_EQ(map.find("region 3"), std::string::npos);

  const std::string overlay = expect_figure(stems[3]);
  for (const std::string& s : std::vector<std::string>{"circle_cw", "x [m]", "reference", "nominal replay",
                                                       "corrected replay", kFinding})
    expect_contains(overlay, s, "overlay.svg");
}

TEST_F(DiagnosisFiguresTest, NoFindingStillDrawsEveryFigure) {
  const DiagnosisFigureData d = synthetic(false);
  const auto stems = diagnosis_figures(dir_.path(), d);
  ASSERT_EQ(stems.size(), 4u);
  const std::string time = expect_figure(stems[0]);
  expect_contains(time, "before: nominal model", "residual_time.svg");
  EXPECT_EQ(time.find("after:"), std::string::npos);
  const std::string cond = expect_figure(stems[1]);
  expect_contains(cond, "before: median", "residual_condition.svg");
  EXPECT_EQ(cond.find("after"), std::string::npos);
  expect_figure(stems[2]);
  expect_contains(expect_figure(stems[3]), "no finding", "overlay.svg");
}

TEST_F(DiagnosisFiguresTest, WithoutConditionTheScatterIsSkipped) {
  DiagnosisFigureData d = synthetic(false);
  d.condition_value.clear();
  d.before_residual.clear();
  d.after_residual.clear();
  d.regions.clear();
  d.flagged.clear();
  const auto stems = diagnosis_figures(dir_.path(), d);
  EXPECT_EQ(stems, (std::vector<fs::path>{dir_ / "residual_time", dir_ / "map", dir_ / "overlay"}));
  EXPECT_EQ(dir_.entries(), 6u);
  const std::string map = expect_figure(dir_ / "map");
  EXPECT_EQ(map.find("region 1"), std::string::npos);
  EXPECT_EQ(map.find("residual above noise"), std::string::npos);
}

// Malformed input throws before any file is written; the message names the
// field and both lengths.
TEST_F(DiagnosisFiguresTest, MismatchedLengthsThrowNamingTheField) {
  const auto expect_bad = [this](DiagnosisFigureData d, const std::vector<std::string>& words) {
    try {
      diagnosis_figures(dir_.path(), d);
      ADD_FAILURE() << "expected std::invalid_argument for " << words.front();
    } catch (const std::invalid_argument& e) {
      for (const auto& w : words)
        EXPECT_NE(std::string(e.what()).find(w), std::string::npos) << e.what() << " lacks " << w;
    }
    EXPECT_EQ(dir_.entries(), 0u) << words.front();
  };
  DiagnosisFigureData d = synthetic(true);
  d.before_pos_err_m.pop_back();
  expect_bad(d, {"before_pos_err_m", "600", "t_s", "601"});
  d = synthetic(true);
  d.after_pos_err_m.push_back(0.0);
  expect_bad(d, {"after_pos_err_m", "602", "601"});
  d = synthetic(true);
  d.after_residual.resize(10);
  expect_bad(d, {"after_residual", "10", "condition_value", "6000"});
  d = synthetic(true);
  d.before_residual.resize(5999);
  expect_bad(d, {"before_residual", "5999", "6000"});
  d = synthetic(true);
  d.ref_y_m.pop_back();
  expect_bad(d, {"ref_y_m", "600", "ref_x_m", "601"});
  d = synthetic(true);
  d.flagged.resize(3);
  expect_bad(d, {"flagged", "3", "601"});
  d = synthetic(true);
  d.overlay[1].ys_m.resize(7);
  expect_bad(d, {"nominal replay", "601", "7"});
  d = synthetic(true);
  d.condition_value.clear();
  expect_bad(d, {"before_residual", "condition_value"});
  d = synthetic(true);
  d.segments.push_back({5.0, 4.0});
  expect_bad(d, {"segments[2]"});
  d = synthetic(true);
  d.regions.push_back({1.0, 0.0, 0.0, 1.0});
  expect_bad(d, {"regions[2]"});
  d = synthetic(true);
  d.t_s.clear();
  expect_bad(d, {"t_s"});
  d = synthetic(true);
  d.overlay.clear();
  expect_bad(d, {"overlay"});
}

TEST(DiagnosisFiguresBinnedMedian, MediansOfQuantileGroups) {
  // x = 0..99 shuffled, y = 2x + 1: 10 groups of 10 consecutive x values.
  std::vector<double> x(100), y(100);
  for (int i = 0; i < 100; ++i) x[i] = i;
  std::mt19937 rng(99);
  std::shuffle(x.begin(), x.end(), rng);
  for (int i = 0; i < 100; ++i) y[i] = 2.0 * x[i] + 1.0;
  x.push_back(std::numeric_limits<double>::quiet_NaN()), y.push_back(1e9);  // rows with a NaN are left out
  x.push_back(1e9), y.push_back(std::numeric_limits<double>::quiet_NaN());
  const BinnedMedian b = binned_median(x, y, 10);
  ASSERT_EQ(b.x.size(), 10u);
  for (int g = 0; g < 10; ++g) {
    EXPECT_DOUBLE_EQ(b.x[g], 10.0 * g + 4.5);
    EXPECT_DOUBLE_EQ(b.y[g], 2.0 * (10.0 * g + 4.5) + 1.0);
  }
  // 7 rows into 3 groups: sizes 3, 2, 2.
  const BinnedMedian u = binned_median({6, 5, 4, 3, 2, 1, 0}, {0, 0, 0, 0, 0, 10, 20}, 3);
  EXPECT_EQ(u.x, (std::vector<double>{1, 3.5, 5.5}));
  EXPECT_EQ(u.y, (std::vector<double>{10, 0, 0}));
  // Fewer rows than bins, no row, bad input.
  EXPECT_EQ(binned_median({1, 2}, {3, 4}, 15).x.size(), 2u);
  EXPECT_TRUE(binned_median({std::numeric_limits<double>::quiet_NaN()}, {1}, 15).x.empty());
  EXPECT_THROW(binned_median({1, 2}, {1}, 3), std::invalid_argument);
  EXPECT_THROW(binned_median({1}, {1}, 0), std::invalid_argument);
}

class DiagnosisReportTest : public DiagnosisFiguresTest {};

const std::vector<std::string> kSummary = {
    "finding: lateral_skid k = 0.021 ± 0.002 (p < 0.001)",
    "region 1: x in [-2.8, 2.8] m & y in [-5.3, -4.0] m",
};
const std::string kJson = R"({"track": "circle<cw>", "effect": "lateral_skid", "note": "a & b"})";

TEST_F(DiagnosisReportTest, PageInlinesEveryFigureSummaryAndEscapedJson) {
  const fs::path out = dir_ / "new" / "report";  // created on the way
  write_diagnosis_report(out, synthetic(true), kSummary, kJson);
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(out)) {
    ++n;
    EXPECT_NE(e.path().filename().string().front(), '.') << "staging left: " << e.path();
  }
  EXPECT_EQ(n, 9u);  // 4 figures × (png, svg) + index.html
  for (const char* stem : {"residual_time", "residual_condition", "map", "overlay"}) expect_figure(out / stem);

  const std::string html = slurp(out / "index.html");
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  expect_contains(html, "<title>odotune diagnose: circle_cw</title>", "index.html");
  EXPECT_EQ(count(html, "<svg"), 4u);
  EXPECT_EQ(count(html, "</svg>"), 4u);
  EXPECT_EQ(count(html, "<figcaption>"), 4u);
  EXPECT_EQ(html.find("<?xml"), std::string::npos);
  // Every figure's ids are prefixed, so none is shared between figures.
  for (const char* prefix : {"id=\"residual_time-", "id=\"residual_condition-", "id=\"map-", "id=\"overlay-"})
    expect_contains(html, prefix, "index.html");
  for (const char* label : {"|v*w| [m/s^2]", "region 1", "corrected replay", "located segment"})
    expect_contains(html, label, "index.html");
  expect_contains(html, "<li>finding: lateral_skid k = 0.021 ± 0.002 (p &lt; 0.001)</li>", "index.html");
  expect_contains(html, "<li>region 1: x in [-2.8, 2.8] m &amp; y in [-5.3, -4.0] m</li>", "index.html");
  expect_contains(html,
                  "<pre>{&quot;track&quot;: &quot;circle&lt;cw&gt;&quot;, &quot;effect&quot;: "
                  "&quot;lateral_skid&quot;, &quot;note&quot;: &quot;a &amp; b&quot;}</pre>",
                  "index.html");
  EXPECT_EQ(html.find("circle<cw>"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("href=\"http"), std::string::npos);
  EXPECT_EQ(html.find("src=\""), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
}

TEST_F(DiagnosisReportTest, FailingGnuplotLeavesNoPage) {
  const fs::path out = dir_ / "report";
  {
    const PathOverride no_gnuplot((dir_ / "empty-path").string());
    EXPECT_THROW(write_diagnosis_report(out, synthetic(true), kSummary, kJson), std::runtime_error);
  }
  EXPECT_TRUE(fs::is_directory(out));
  EXPECT_TRUE(fs::is_empty(out));  // no page, no figure, no staging folder
}

TEST_F(DiagnosisReportTest, FailureKeepsTheEarlierReportAsItWas) {
  const fs::path out = dir_ / "report";
  write_diagnosis_report(out, synthetic(true), kSummary, kJson);
  const std::string page = slurp(out / "index.html");
  const std::string map_svg = slurp(out / "map.svg");
  {
    const PathOverride no_gnuplot((dir_ / "empty-path").string());
    EXPECT_THROW(write_diagnosis_report(out, synthetic(false), {"other"}, "{}"), std::runtime_error);
  }
  DiagnosisFigureData bad = synthetic(false);
  bad.ref_x_m.pop_back();
  EXPECT_THROW(write_diagnosis_report(out, bad, {"other"}, "{}"), std::invalid_argument);
  EXPECT_EQ(slurp(out / "index.html"), page);
  EXPECT_EQ(slurp(out / "map.svg"), map_svg);
  EXPECT_EQ(static_cast<std::size_t>(std::distance(fs::directory_iterator(out), fs::directory_iterator{})), 9u);
}

TEST_F(DiagnosisReportTest, NoFindingAndNoConditionRemovesAStaleScatter) {
  const fs::path out = dir_ / "report";
  write_diagnosis_report(out, synthetic(true), kSummary, kJson);
  ASSERT_TRUE(fs::exists(out / "residual_condition.svg"));
  DiagnosisFigureData d = synthetic(false);
  d.condition_value.clear();
  d.before_residual.clear();
  write_diagnosis_report(out, d, {"no finding"}, "{\"finding\": null}");
  EXPECT_FALSE(fs::exists(out / "residual_condition.svg"));
  EXPECT_FALSE(fs::exists(out / "residual_condition.png"));
  const std::string html = slurp(out / "index.html");
  EXPECT_EQ(count(html, "<svg"), 3u);
  EXPECT_EQ(html.find("residual_condition"), std::string::npos);
  expect_contains(html, "<li>no finding</li>", "index.html");
  expect_contains(html, "only the nominal model", "index.html");
  EXPECT_EQ(html.find("corrected replay"), std::string::npos);
}

}  // namespace
}  // namespace odotune::results

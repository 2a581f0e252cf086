// The estimates-over-time figure (odotune/results/calibration_figures.h). gnuplot is
// a build dependency (scripts/install-deps.sh): when it is missing these
// tests FAIL on purpose, as the study's figure tests do.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

#include <odotune/results/calibration_figures.h>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace odotune::results {
namespace {
namespace fs = std::filesystem;
using testing_support::TempDir;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using testing_support::slurp;

bool is_png(const fs::path& p) {
  const std::string s = slurp(p);
  return s.size() > 8 && s.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) == 0;
}

// An estimate converging exponentially from `start` to `truth` (time
// constant 10 s) with seeded noise, 10 Hz over 60 s, with a shrinking sd.
EstimateSeries converging(const std::string& name, double start, double truth, std::uint32_t seed,
                          bool with_sd) {
  EstimateSeries s;
  s.name = name;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 2e-4);
  for (int i = 0; i <= 600; ++i) {
    const double t = i / 10.0;
    s.t_s.push_back(t);
    s.value_m.push_back(truth + (start - truth) * std::exp(-t / 10.0) + noise(rng));
    if (with_sd) s.sd_m.push_back(0.01 * std::exp(-t / 15.0) + 1e-4);
  }
  return s;
}

EstimateSeries flat(const std::string& name, double value, bool truth) {
  EstimateSeries s;
  s.name = name;
  s.t_s = {0.0, 60.0};
  s.value_m = {value, value};
  s.truth = truth;
  return s;
}

CalibrationFigureData two_methods() {
  CalibrationFigureData d;
  d.title = "chair_a: radii over time";
  EstimateSeries apf_r = converging("R_R adaptive-pf", 0.335, 0.32384, 1, true);
  EstimateSeries dkf_r = converging("R_R dkf", 0.32, 0.32384, 2, false);
  apf_r.colour = 0;
  dkf_r.colour = 1;
  EstimateSeries truth = flat("R_R true", 0.32384, true);
  d.radii = {apf_r, dkf_r, truth};
  d.wheel_base = {converging("D adaptive-pf", 0.70, 0.65, 3, true), flat("D true", 0.65, true)};
  d.markers = {{30.0, "radius step"}};
  return d;
}

TEST(CalibrationFigure, WritesPngAndSvgWithPanelsLegendsAndMarkers) {
  TempDir dir;
  const fs::path stem = dir / "radii";
  calibration_estimates_figure(stem, two_methods());
  ASSERT_TRUE(is_png(dir / "radii.png"));
  const std::string svg = slurp(dir / "radii.svg");
  for (const char* text :
       {"chair_a: radii over time", "wheel radius [m]", "wheel base [m]", "time [s]", "R_R adaptive-pf",
        "R_R dkf", "R_R true", "D adaptive-pf", "D true", "radius step", "estimate ± 1 sd"})
    EXPECT_NE(svg.find(text), std::string::npos) << text;
  EXPECT_EQ(dir.entries(), 2u);  // the two figures, no leftovers
}

TEST(CalibrationFigure, OnePanelWithoutWheelBaseAndNoBandWithoutSd) {
  TempDir dir;
  CalibrationFigureData d;
  d.title = "radii only";
  d.radii = {converging("R_L", 0.30, 0.3168, 4, false), flat("R_L true", 0.3168, true)};
  d.radii[0].value_m[100] = kNaN;  // a gap is allowed
  d.time_label = "elapsed [s]";
  calibration_estimates_figure(dir / "one", d);
  const std::string svg = slurp(dir / "one.svg");
  EXPECT_NE(svg.find("wheel radius [m]"), std::string::npos);
  EXPECT_NE(svg.find("elapsed [s]"), std::string::npos);
  EXPECT_EQ(svg.find("wheel base [m]"), std::string::npos);
  EXPECT_EQ(svg.find("± 1 sd"), std::string::npos);
  EXPECT_TRUE(is_png(dir / "one.png"));
}

TEST(CalibrationFigure, BadInputThrowsBeforeWritingAnything) {
  TempDir dir;
  CalibrationFigureData empty;
  EXPECT_THROW(calibration_estimates_figure(dir / "e", empty), std::invalid_argument);

  CalibrationFigureData mismatched = two_methods();
  mismatched.radii[1].value_m.pop_back();
  try {
    calibration_estimates_figure(dir / "m", mismatched);
    ADD_FAILURE() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("R_R dkf"), std::string::npos) << what;
    EXPECT_NE(what.find("601"), std::string::npos) << what;
    EXPECT_NE(what.find("600"), std::string::npos) << what;
  }

  CalibrationFigureData bad_sd = two_methods();
  bad_sd.radii[0].sd_m.resize(3);
  EXPECT_THROW(calibration_estimates_figure(dir / "s", bad_sd), std::invalid_argument);

  CalibrationFigureData all_nan = two_methods();
  for (auto& s : all_nan.wheel_base) std::fill(s.value_m.begin(), s.value_m.end(), kNaN);
  EXPECT_THROW(calibration_estimates_figure(dir / "n", all_nan), std::invalid_argument);

  CalibrationFigureData bad_marker = two_methods();
  bad_marker.markers.push_back({kNaN, "x"});
  EXPECT_THROW(calibration_estimates_figure(dir / "k", bad_marker), std::invalid_argument);

  EXPECT_EQ(dir.entries(), 0u);
}

TEST(CalibrationFigure, MissingDirectoryIsAnErrorAndWritesNothing) {
  TempDir dir;
  EXPECT_THROW(calibration_estimates_figure(dir / "no_such_dir" / "f", two_methods()), std::runtime_error);
  EXPECT_EQ(dir.entries(), 0u);
}

}  // namespace
}  // namespace odotune::results

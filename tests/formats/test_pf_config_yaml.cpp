// The tuned PF settings file (odotune-pf-config/1, odotune/formats/pf_config_yaml.h):
// written and read back bit for bit, applied to a calibrator's parameters,
// and every reading error one line with file and line.
#include <odotune/formats/pf_config_yaml.h>

#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/calibration/calibration_objective.h>
#include <odotune/core/failure.h>

#include "support/temp_dir.h"

namespace odotune::formats {
namespace {

using testing_support::TempDir;

odotune::formats::PfConfig sample() {
  odotune::formats::PfConfig c;
  c.method = calibration::CalibrationMethod::pf;
  c.resampler = filters::Resampler::residual;
  c.policy = filters::ResamplePolicy::max_weight;
  c.particles = 1234;
  c.params = {0.1 + 0.2, 37.000000000000014, 1.0 / 3.0 * 1e-3, 0.0123456789012345, 2.5};
  c.comment = "provenance line 1\nline 2";
  return c;
}

TEST(PfConfigYaml, RoundTripsBitForBit) {
  TempDir tmp;
  const auto path = tmp / "pf.yaml";
  odotune::formats::write_pf_config(sample(), path);
  const odotune::formats::PfConfig back = odotune::formats::read_pf_config(path);
  EXPECT_EQ(back.method, calibration::CalibrationMethod::pf);
  EXPECT_EQ(back.resampler, filters::Resampler::residual);
  EXPECT_EQ(back.policy, filters::ResamplePolicy::max_weight);
  EXPECT_EQ(back.particles, 1234);
  EXPECT_EQ(back.params, sample().params);
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "# provenance line 1");
}

TEST(PfConfigYaml, AppliesTheFileAndKeepsTheRobotsRangesAndSeed) {
  filters::PfCalibratorParams base;
  base.wheel_radius_left_m = {0.04, 0.06};
  base.seed = 99;
  base.adaptive = true;
  const filters::PfCalibratorParams p = odotune::formats::apply_pf_config(sample(), base);
  EXPECT_FALSE(p.adaptive);  // method pf
  EXPECT_EQ(p.resampler, filters::Resampler::residual);
  EXPECT_EQ(p.policy, filters::ResamplePolicy::max_weight);
  EXPECT_EQ(p.particles, 1234);
  EXPECT_DOUBLE_EQ(p.neff_fraction, 0.1 + 0.2);
  EXPECT_NEAR(p.random_walk_sigma_m, 2.5e-3, 1e-18);  // mm in the file, m inside
  EXPECT_EQ(p.wheel_radius_left_m.lo, 0.04);
  EXPECT_EQ(p.seed, 99u);
}

// Writes `text` and expects reading it to fail with "FILE:LINE:" and `what`.
void expect_error(const std::string& text, int line, const std::string& what) {
  TempDir tmp;
  const auto path = tmp / "bad.yaml";
  std::ofstream(path) << text;
  try {
    odotune::formats::read_pf_config(path);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const odotune::core::Failure& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path.string() + ":" + std::to_string(line) + ":"), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

const std::string kGood =
    "format: odotune-pf-config/1\nmethod: adaptive-pf\nresampler: systematic\npolicy: neff\n"
    "particles: 8000\nparams:\n  neff_fraction: 0.5\n  max_weight_ratio: 10\n  alpha: 0.0001\n"
    "  dispersion_per_particle_mm: 0.01\n  random_walk_sigma_mm: 0.5\n";

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  s.replace(s.find(from), from.size(), to);
  return s;
}

TEST(PfConfigYaml, ReadsTheDocumentedExample) {
  TempDir tmp;
  std::ofstream(tmp / "ok.yaml") << kGood;
  const odotune::formats::PfConfig c = odotune::formats::read_pf_config(tmp / "ok.yaml");
  EXPECT_EQ(c.method, calibration::CalibrationMethod::adaptive_pf);
  EXPECT_EQ(c.particles, 8000);
  const std::vector<double> paper = calibration::calibration_params_of(
      filters::PfCalibratorParams::adaptive_defaults());
  ASSERT_EQ(c.params.size(), paper.size());
  for (std::size_t i = 0; i < paper.size(); ++i) EXPECT_NEAR(c.params[i], paper[i], 1e-12 * paper[i]) << i;
}

TEST(PfConfigYaml, ErrorsNameFileAndLine) {
  expect_error(replaced(kGood, "odotune-pf-config/1", "odotune-ekf-config/1"), 1, "format");
  expect_error(replaced(kGood, "method: adaptive-pf", "method: dkf"), 2, "pf or adaptive-pf");
  expect_error(replaced(kGood, "resampler: systematic", "resampler: lottery"), 3, "resampler");
  expect_error(replaced(kGood, "policy: neff", "policy: often"), 4, "policy");
  expect_error(replaced(kGood, "particles: 8000", "particles: -3"), 5, "particles");
  expect_error(replaced(kGood, "  alpha: 0.0001", "  alpah: 0.0001"), 9, "alpah");
  expect_error(replaced(kGood, "  alpha: 0.0001", "  alpha: lots"), 9, "alpha");
  expect_error(replaced(kGood, "  neff_fraction: 0.5", "  neff_fraction: 1.5"), 7, "neff_fraction");
  expect_error(replaced(kGood, "  random_walk_sigma_mm: 0.5\n", ""), 7, "random_walk_sigma_mm");
  expect_error(kGood + "threads: 2\n", 12, "threads");
}

TEST(PfConfigYaml, MissingFileIsOneLine) {
  TempDir tmp;
  EXPECT_THROW(odotune::formats::read_pf_config(tmp / "none.yaml"), odotune::core::Failure);
}

}  // namespace
}  // namespace odotune::formats

// The tuner on a real recording (OptiOdom, Sousa et al. 2022, MIT licence:
// ../shared/data/real/optiodom_diff), with position fixes made from its
// ground truth as in the study: import → fixes → tune beats the baseline.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "support/cli_runner.h"

namespace odotune::cli {
namespace {

using testing_support::run_cli;
using testing_support::TempDir;

TEST(CliRealData, OptiOdomRunTunesAfterSyntheticFixes) {
  TempDir tmp;
  const std::string run = std::string(ODOTUNE_SHARED_DIR) +
                          "/data/real/optiodom_diff/free/020120212354/020120212354_run-01.csv";
  const auto raw = tmp / "raw.csv", aps = tmp / "aps.csv", json_file = tmp / "t.json";
  ASSERT_EQ(run_cli(fmt::format("import optiodom {} -o {}", run, raw.string())).exit_code, 0);

  // Without fixes there is nothing to tune: one clear line, non-zero exit.
  const auto refused = run_cli(fmt::format("tune --track {}", raw.string()));
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("no position fixes"), std::string::npos) << refused.err;

  ASSERT_EQ(run_cli(fmt::format("fixes {} -o {} --seed 7", raw.string(), aps.string())).exit_code, 0);
  const auto r = run_cli(
      fmt::format("tune --track {} --model alpha --mode 1 --particles 12 --iterations 15 --json {}",
                  aps.string(), json_file.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(testing_support::slurp(json_file));
  EXPECT_LT(j["tuned"]["rmse_m"].get<double>(), j["baseline"]["rmse_m"].get<double>());
  EXPECT_EQ(j["divergences"]["non_finite"], 0);
}

// Calibration on real recordings (docs/calibration/real-data.md, protocol A):
// calibrated on three OptiOdom runs, replayed on four others. The pose fit
// (batch) and the adaptive PF must improve every held-out run over the
// nominal parameters, the pose fit's mean below 25 mm (19.3 mm in the docs).
TEST(CliRealData, OptiOdomCalibrationImprovesEveryHeldOutRun) {
  TempDir tmp;
  const std::string oo = std::string(ODOTUNE_SHARED_DIR) + "/data/real/optiodom_diff/";
  const auto import = [&](const std::string& run) {
    const auto out = tmp / (run.substr(run.rfind('/') + 1) + ".csv");
    EXPECT_EQ(run_cli(fmt::format("import optiodom {}{}.csv -o {}", oo, run, out.string())).exit_code, 0)
        << run;
    return out.string();
  };
  std::string fit, held;
  for (const char* r : {"circular/231220200146/231220200146_run-01", "square/231220200045/231220200045_run-01",
                        "free/030120210001/030120210001_run-01"})
    fit += " --track " + import(r);
  for (const char* r : {"circular/231220200146/231220200146_run-02", "square/231220200045/231220200045_run-02",
                        "free/020120212354/020120212354_run-01", "free/030120210001/030120210001_run-02"})
    held += " --track " + import(r);
  for (const std::string method : {"batch", "adaptive-pf"}) {
    const auto cfg = tmp / (method + ".yaml"), json_file = tmp / (method + ".json");
    const auto r = run_cli(fmt::format("calibrate{} --method {} --ext-from-gt 10 --threads 1 --config-out {}",
                                       fit, method, cfg.string()));
    ASSERT_EQ(r.exit_code, 0) << method << ": " << r.err;
    ASSERT_EQ(run_cli(fmt::format("calibrate{} --apply {} --json {}", held, cfg.string(), json_file.string()))
                  .exit_code,
              0);
    const auto j = nlohmann::json::parse(testing_support::slurp(json_file));
    ASSERT_EQ(j["tracks"].size(), 4u);
    for (const auto& t : j["tracks"])
      EXPECT_LT(t["calibrated"]["pose_rmse_m"].get<double>(), t["nominal"]["pose_rmse_m"].get<double>())
          << method << " " << t["track"];
    if (method == "batch") {
      EXPECT_LT(j["mean"]["calibrated"]["pose_rmse_m"].get<double>(), 0.025);
    }
  }
}

// A copy of a track without its ground-truth columns (gt_*), so that a fit
// can only use its fixes (as reproduce/strip_ground_truth.py).
void strip_ground_truth(const std::filesystem::path& in, const std::filesystem::path& out) {
  std::ifstream f(in);
  std::ofstream o(out);
  std::vector<bool> keep;
  for (std::string line; std::getline(f, line);) {
    if (line.starts_with("#")) {
      o << line << "\n";
      continue;
    }
    std::stringstream cells(line);
    std::vector<std::string> row;
    for (std::string c; std::getline(cells, c, ',');) row.push_back(c);
    if (keep.empty())
      for (const auto& h : row) keep.push_back(!h.starts_with("gt_"));
    std::string kept;
    for (std::size_t i = 0; i < row.size() && i < keep.size(); ++i)
      if (keep[i]) kept += (kept.empty() ? "" : ",") + row[i];
    o << kept << "\n";
  }
}

// The pose fit from fixes alone, on OptiOdom's three 2-3 Jan runs (about
// 200 s of driving): with 0.1-m fixes its file is written; with 1-m fixes it
// shrinks the path towards a point (a wheel radius of under 1 mm), and
// `calibrate` refuses that fit in one line and writes nothing.
TEST(CliRealData, OptiOdomPoseFitFromFixesTooNoisyToCarryTheScaleIsRefused) {
  TempDir tmp;
  const std::string oo = std::string(ODOTUNE_SHARED_DIR) + "/data/real/optiodom_diff/free/";
  for (const std::string sigma : {"0.1", "1"}) {
    std::string tracks;
    for (const char* run : {"020120212354/020120212354_run-01", "030120210001/030120210001_run-01",
                            "030120210001/030120210001_run-02"}) {
      const std::string name = std::string(run).substr(std::string(run).rfind('/') + 1);
      const auto raw = tmp / (name + ".csv"), aps = tmp / (name + "-aps.csv"),
                 only = tmp / (name + "-s" + sigma + ".csv");
      ASSERT_EQ(run_cli(fmt::format("import optiodom {}{}.csv -o {}", oo, run, raw.string())).exit_code, 0);
      ASSERT_EQ(run_cli(fmt::format("fixes {} -o {} --rate-hz 1 --sigma-m {} --seed 1", raw.string(),
                                    aps.string(), sigma))
                    .exit_code,
                0);
      strip_ground_truth(aps, only);
      tracks += " --track " + only.string();
    }
    const auto cfg = tmp / ("cal-s" + sigma + ".yaml");
    const auto r = run_cli(fmt::format("calibrate{} --method batch-pose --config-out {}", tracks,
                                       cfg.string()));
    if (sigma == "0.1") {
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_TRUE(std::filesystem::exists(cfg));
      continue;
    }
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.err.find("calibrate: the fit is not one this robot can have: wheel_radius_"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("nothing was written"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(cfg));
  }
}

}  // namespace
}  // namespace odotune::cli

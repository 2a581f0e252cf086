// The tuner on a real recording (OptiOdom, Sousa et al. 2022, MIT licence:
// ../shared/data/real/optiodom_diff), with position fixes made from its
// ground truth as in the study: import → fixes → tune beats the baseline.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fmt/format.h>

#include "support/cli_runner.h"

namespace odotune {
namespace {

using testing_support::run_cli;
using testing_support::TempDir;

TEST(CliRealData, OptiOdomRunTunesAfterSyntheticFixes) {
  TempDir tmp;
  const std::string run = std::string(ODOTUNE_SHARED_DIR) +
                          "/data/real/optiodom_diff/free/020120212354/020120212354_run-01.csv";
  const auto raw = tmp / "raw.csv", aps = tmp / "aps.csv", json = tmp / "t.json";
  ASSERT_EQ(run_cli(fmt::format("import optiodom {} -o {}", run, raw.string())).exit_code, 0);

  // Without fixes there is nothing to tune: one clear line, non-zero exit.
  const auto refused = run_cli(fmt::format("tune --track {}", raw.string()));
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("no position fixes"), std::string::npos) << refused.err;

  ASSERT_EQ(run_cli(fmt::format("fixes {} -o {} --seed 7", raw.string(), aps.string())).exit_code, 0);
  const auto r = run_cli(
      fmt::format("tune --track {} --model alpha --mode 1 --particles 12 --iterations 15 --json {}",
                  aps.string(), json.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(testing_support::slurp(json));
  EXPECT_LT(j["tuned"]["rmse_m"].get<double>(), j["baseline"]["rmse_m"].get<double>());
  EXPECT_EQ(j["divergences"]["non_finite"], 0);
}

}  // namespace
}  // namespace odotune

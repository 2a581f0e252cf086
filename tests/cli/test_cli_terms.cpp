// Physics outside the list end to end: simulate an
// out-of-round wheel (scenarios/out_of_round.yaml, shortened), diagnose it,
// write the scenario with the discovered terms (--scenario-out), simulate
// that scenario and diagnose again: the same terms come back at the same
// size. The JSON's `model` follows ../shared/specs/diagnosis-output.md.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace odotune::cli {
namespace {

using nlohmann::json;
using testing_support::run_cli;
using testing_support::slurp;
using ::testing::HasSubstr;

// The unexplained finding's terms by name -> coef; fails when there is none.
std::map<std::string, double> found_terms(const json& j) {
  std::map<std::string, double> out;
  for (const json& f : j.at("findings")) {
    if (f.at("effect") != "unexplained" || !f.contains("model")) continue;
    const json& m = f.at("model");
    EXPECT_TRUE(m.at("formula").is_string());
    for (const char* part : {"train", "heldout"})
      for (const char* key : {"before_pos_rmse_m", "after_pos_rmse_m"})
        EXPECT_TRUE(m.at("fit").at(part).at(key).is_number()) << part << "." << key;
    EXPECT_LT(m.at("fit").at("heldout").at("after_pos_rmse_m").get<double>(),
              m.at("fit").at("heldout").at("before_pos_rmse_m").get<double>());
    for (const json& t : m.at("terms")) {
      EXPECT_EQ(t.at("target"), "v_l");
      EXPECT_TRUE(t.at("stderr").is_number());
      out[t.at("name").get<std::string>()] = t.at("coef").get<double>();
    }
  }
  return out;
}

TEST(CliTerms, OutOfRoundRoundTripFindsTheSameTerms) {
  testing_support::TempDir dir;
  // The example scenario with 4 laps instead of 6 (about 2 minutes).
  std::string text = slurp(std::string(ODOTUNE_SOURCE_DIR) + "/scenarios/out_of_round.yaml");
  const auto at = text.find("count: 6");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 8, "count: 4");
  const auto yaml = dir.path() / "oor.yaml";
  std::ofstream(yaml) << text;

  const std::string track = (dir.path() / "oor.csv").string(), first = (dir.path() / "first.json").string();
  const std::string found = (dir.path() / "found.yaml").string();
  auto r = run_cli("simulate " + yaml.string() + " -o " + track);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("diagnose " + track + " --json " + first + " --scenario-out " + found);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("terms outside that list reproduce it: v_l,true = v_l·(1 + 0.0"));
  EXPECT_THAT(r.out, HasSubstr("model: v_l,true"));
  const std::map<std::string, double> a = found_terms(json::parse(slurp(first)));
  ASSERT_EQ(a.count("v_l·sin(φ_l)"), 1u) << json::parse(slurp(first)).at("term_search").dump();
  ASSERT_EQ(a.count("v_l·cos(φ_l)"), 1u);
  EXPECT_NEAR(a.at("v_l·sin(φ_l)"), 0.00921, 0.25 * 0.00921);
  EXPECT_NEAR(a.at("v_l·cos(φ_l)"), 0.00389, 0.25 * 0.00389);
  EXPECT_THAT(slurp(found), HasSubstr("term: \"v_l*sin(phi_l)\""));

  const std::string again = (dir.path() / "again.csv").string(), second = (dir.path() / "second.json").string();
  r = run_cli("simulate " + found + " -o " + again);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(slurp(again), HasSubstr("# sim.terms: v_l += "));
  r = run_cli("diagnose " + again + " --json " + second);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::map<std::string, double> b = found_terms(json::parse(slurp(second)));
  ASSERT_EQ(b.size(), a.size()) << json::parse(slurp(second)).at("term_search").dump();
  for (const auto& [name, coef] : a) {
    ASSERT_EQ(b.count(name), 1u) << name;
    EXPECT_NEAR(b.at(name), coef, 0.25 * std::abs(coef)) << name;
  }
}

TEST(CliTerms, BadTermInAScenarioIsOneLineWithItsLine) {
  testing_support::TempDir dir;
  const auto yaml = dir.path() / "bad.yaml";
  std::ofstream(yaml) << "motion: {segments: [{straight: {distance_m: 1, speed_m_s: 0.5}}]}\n"
                         "terms:\n"
                         "  - {target: v_l, term: \"v_l*sin(phi_l)\", coef: 0.01}\n"
                         "  - {target: v_r, term: \"v_l*cos(phi_l)\", coef: 0.01}\n";
  const auto out = dir.path() / "t.csv";
  const auto r = run_cli("simulate " + yaml.string() + " -o " + out.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("bad.yaml:4: terms[2].term: unknown term 'v_l*cos(phi_l)' for target v_r"));
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace odotune::cli

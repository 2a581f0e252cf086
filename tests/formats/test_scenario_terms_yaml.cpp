// The `terms:` section of scenario YAML (odotune/formats/scenario_yaml.h,
// odotune/sim/model_terms.h): read in both name forms, written back to the same
// terms, errors naming file, line and field.
#include <stdexcept>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/formats/scenario_yaml.h>

namespace odotune::formats {
namespace {

using ::testing::HasSubstr;

const std::string kTermsMotion = "motion: {segments: [{straight: {distance_m: 2, speed_m_s: 0.5}}]}\n";

TEST(ScenarioTermsYaml, ReadsBothFormsAndWritesThemBack) {
  const sim::Scenario sc = parse_scenario(kTermsMotion +
                                              "terms:\n"
                                              "  - {target: v_l, term: \"v_l*sin(phi_l)\", coef: 0.0092}\n"
                                              "  - {target: v_r, term: \"|v·w|\", coef: -0.02}\n"
                                              "  - {target: v_l, term: \"v_l·cos(2φ_l)\", coef: 1e-3}\n",
                                          "t.yaml");
  ASSERT_EQ(sc.terms.size(), 3u);
  EXPECT_EQ(sc.terms[0].target, sim::TermTarget::v_l);
  EXPECT_EQ(sc.terms[0].basis, sim::TermBasis::sin_1);
  EXPECT_EQ(sc.terms[0].coef, 0.0092);
  EXPECT_EQ(sc.terms[1].target, sim::TermTarget::v_r);
  EXPECT_EQ(sc.terms[1].basis, sim::TermBasis::turn_speed);
  EXPECT_EQ(sc.terms[2].basis, sim::TermBasis::cos_2);
  const std::string text = scenario_to_yaml(sc, "");
  EXPECT_THAT(text, HasSubstr("  - {target: v_r, term: \"|v*w|\", coef: -0.02}\n"));
  const sim::Scenario back = parse_scenario(text, "back.yaml");
  ASSERT_EQ(back.terms.size(), sc.terms.size());
  for (std::size_t i = 0; i < sc.terms.size(); ++i) {
    EXPECT_EQ(back.terms[i].target, sc.terms[i].target);
    EXPECT_EQ(back.terms[i].basis, sc.terms[i].basis);
    EXPECT_EQ(back.terms[i].coef, sc.terms[i].coef);
  }
  EXPECT_THAT(scenario_to_yaml(parse_scenario(kTermsMotion, "none.yaml"), ""),
              ::testing::Not(HasSubstr("terms")));
}

TEST(ScenarioTermsYaml, ErrorsNameFileLineAndField) {
  auto error = [](const std::string& terms) {
    try {
      (void)parse_scenario(kTermsMotion + terms, "bad.yaml");
    } catch (const ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(error("terms: 3\n"), HasSubstr("bad.yaml:2: terms: expected a list of"));
  EXPECT_THAT(error("terms:\n  - {target: v_x, term: \"1\", coef: 1}\n"),
              HasSubstr("bad.yaml:3: terms[1].target: unknown term target 'v_x'; expected v_l or v_r"));
  EXPECT_THAT(error("terms:\n  - {target: v_l, term: \"v_l*sin(phi_l)\"}\n"),
              HasSubstr("bad.yaml:3: terms[1]: missing 'coef'"));
  EXPECT_THAT(error("terms:\n  - {target: v_l, term: \"v_l\", coef: 1, wheel: left}\n"),
              HasSubstr("unknown key 'wheel' in terms[1]"));
  EXPECT_THAT(error("terms:\n  - {target: v_l, term: \"v_l\", coef: x}\n"),
              HasSubstr("bad.yaml:3: terms[1].coef: expected a finite number, got 'x'"));
  EXPECT_THAT(
      error("terms:\n  - {target: v_l, term: \"1\", coef: 1}\n  - {target: v_l, term: \"1\", coef: 2}\n"),
      HasSubstr("bad.yaml:4: terms: term 2 (1 on v_l) is given twice"));
}

}  // namespace
}  // namespace odotune::formats

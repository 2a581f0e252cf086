// The effect vocabulary (odotune/sim/effects.h): names verbatim from the spec,
// command-line specs, validation messages, override semantics.
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/sim/effects.h>

namespace odotune::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::string error_of(const std::string& spec) {
  try {
    (void)parse_effect_spec(spec);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// The effect and parameter names as written in physics-effects.md (typed in
// from the spec, not from the code).
const std::map<std::string, std::vector<std::string>> kSpecNames = {
    {"radius_error", {"scale_l", "scale_r"}},
    {"wheel_base_error", {"scale"}},
    {"radius_step", {"t", "scale_l", "scale_r"}},
    {"speed_radius", {"c"}},
    {"lateral_skid", {"k"}},
    {"longitudinal_slip", {"k"}},
    {"slip_zone", {"x0", "x1", "y0", "y1", "s_l", "s_r"}},
    {"gyro_bias", {"b"}},
    {"gyro_scale", {"s"}},
    {"actuator_lag", {"tau"}},
    {"time_offset", {"dt"}},
    {"odometry_bias", {"b_v", "b_w"}},
};

TEST(EffectTable, NamesAreTheSpecsVerbatim) {
  ASSERT_EQ(effect_table().size(), kSpecNames.size());
  for (const auto& e : effect_table()) {
    const auto it = kSpecNames.find(std::string(e.name));
    ASSERT_NE(it, kSpecNames.end()) << e.name;
    std::vector<std::string> params;
    for (const auto& p : e.params) params.emplace_back(p.name);
    EXPECT_EQ(params, it->second) << e.name;
  }
}

// Cross-check against the spec file itself, when the shared folder is there.
TEST(EffectTable, MatchesTheSpecFileTable) {
  const std::filesystem::path spec = std::filesystem::path(ODOTUNE_SHARED_DIR) / "specs/physics-effects.md";
  if (!std::filesystem::exists(spec)) GTEST_SKIP() << "no " << spec;
  std::ifstream in(spec);
  std::string line;
  std::set<std::string> seen;
  const std::regex row(R"(^\| `([a-z_]+)` \| (.*?) \|)");
  const std::regex ticked("`([a-z_0-9]+)`");
  while (std::getline(in, line)) {
    std::smatch m;
    if (!std::regex_search(line, m, row)) continue;
    const std::string name = m[1];
    const EffectInfo* info = find_effect(name);
    ASSERT_NE(info, nullptr) << "spec effect " << name << " missing from the table";
    const std::string cell = m[2];
    std::vector<std::string> params;
    for (auto it = std::sregex_iterator(cell.begin(), cell.end(), ticked); it != std::sregex_iterator(); ++it)
      params.push_back((*it)[1]);
    std::vector<std::string> ours;
    for (const auto& p : info->params) ours.emplace_back(p.name);
    EXPECT_EQ(params, ours) << name;
    seen.insert(name);
  }
  EXPECT_EQ(seen.size(), effect_table().size());
}

TEST(EffectTable, DefaultsAreInsideTheirRangesAndNoOps) {
  for (const auto& e : effect_table())
    for (const auto& p : e.params) {
      EXPECT_LT(p.min, p.max) << e.name << "." << p.name;
      if (!p.required) {
        EXPECT_TRUE(check_param(e, p, p.default_value, nullptr)) << e.name << "." << p.name;
      }
    }
}

TEST(EffectSpec, ParsesTheBriefsExamples) {
  const EffectSpec a = parse_effect_spec("lateral_skid:k=0.02");
  EXPECT_EQ(a.name, "lateral_skid");
  ASSERT_EQ(a.values.size(), 1u);
  EXPECT_EQ(a.values[0].first, "k");
  EXPECT_DOUBLE_EQ(a.values[0].second, 0.02);

  const EffectSpec b = parse_effect_spec(" radius_error : scale_l = 0.995 , scale_r=1.004 ");
  EXPECT_EQ(b.name, "radius_error");
  ASSERT_EQ(b.values.size(), 2u);
  EXPECT_EQ(b.values[0], (std::pair<std::string, double>{"scale_l", 0.995}));
  EXPECT_EQ(b.values[1], (std::pair<std::string, double>{"scale_r", 1.004}));

  const EffectSpec c = parse_effect_spec("time_offset:dt=-2.5e-2");
  EXPECT_DOUBLE_EQ(c.values.at(0).second, -0.025);
}

TEST(EffectSpec, UnknownEffectNamesTheValidOnesAndSuggests) {
  const std::string e = error_of("lateral_skd:k=0.1");
  EXPECT_THAT(e, AllOf(HasSubstr("unknown effect 'lateral_skd'"), HasSubstr("did you mean 'lateral_skid'"),
                       HasSubstr("radius_error"), HasSubstr("time_offset")));
  EXPECT_EQ(e.find('\n'), std::string::npos);
  EXPECT_THAT(error_of("warp_drive"),
              AllOf(HasSubstr("unknown effect 'warp_drive'"), ::testing::Not(HasSubstr("did you mean"))));
}

TEST(EffectSpec, UnknownParameterNamesTheValidOnes) {
  EXPECT_THAT(error_of("radius_error:scale=1.01"),
              AllOf(HasSubstr("no parameter 'scale'"), HasSubstr("scale_l, scale_r")));
  EXPECT_THAT(error_of("slip_zone:x0=0,x1=1,y0=0,y1=1,sl=0.1"),
              AllOf(HasSubstr("'sl'"), HasSubstr("did you mean 's_l'")));
}

TEST(EffectSpec, BadValuesAreNamed) {
  EXPECT_THAT(error_of("lateral_skid:k=abc"),
              AllOf(HasSubstr("lateral_skid.k"), HasSubstr("'abc'"), HasSubstr("not a number")));
  EXPECT_THAT(error_of("lateral_skid:k=0.02x"), HasSubstr("'0.02x'"));
  EXPECT_THAT(error_of("lateral_skid:k="), HasSubstr("not a number"));
  EXPECT_THAT(error_of("lateral_skid:k=nan"), HasSubstr("lateral_skid.k"));
  EXPECT_THAT(error_of("radius_error:scale_l=3"),
              AllOf(HasSubstr("radius_error.scale_l = 3"), HasSubstr("out of range [0.5, 1.5]")));
  EXPECT_THAT(error_of("actuator_lag:tau=0"), HasSubstr("out of range (0, 5]"));
  EXPECT_THAT(error_of("lateral_skid:k"), HasSubstr("not PARAM=VALUE"));
  EXPECT_THAT(error_of("lateral_skid:k=0.1,k=0.2"), HasSubstr("given twice"));
  EXPECT_THAT(error_of(":k=1"), HasSubstr("missing effect name"));
}

TEST(ApplyEffect, SwitchesOnWithDefaultsAndRequiresRequired) {
  Effects fx;
  apply_effect(fx, parse_effect_spec("radius_error:scale_r=1.01"));
  ASSERT_TRUE(fx.radius_error);
  EXPECT_EQ(fx.radius_error->scale_l, 1.0);
  EXPECT_EQ(fx.radius_error->scale_r, 1.01);

  try {
    apply_effect(fx, parse_effect_spec("gyro_bias"));
    FAIL() << "gyro_bias without b accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("gyro_bias"), HasSubstr("needs parameter b")));
  }
  EXPECT_FALSE(fx.gyro_bias) << "a failed apply must leave the effects unchanged";
}

TEST(ApplyEffect, OdometryBiasParametersAreOptionalAndBounded) {
  Effects fx;
  apply_effect(fx, parse_effect_spec("odometry_bias:b_w=-0.01"));
  ASSERT_TRUE(fx.odometry_bias);
  EXPECT_EQ(fx.odometry_bias->b_v, 0.0);  // not given: no offset
  EXPECT_EQ(fx.odometry_bias->b_w, -0.01);
  EXPECT_EQ(format_effects(fx), "odometry_bias:b_v=0,b_w=-0.01");
  EXPECT_THAT(error_of("odometry_bias:b_v=0.6"),
              AllOf(HasSubstr("odometry_bias.b_v = 0.6"), HasSubstr("out of range [-0.5, 0.5] m/s")));
  EXPECT_THAT(error_of("odometry_bias:b_w=-0.51"), HasSubstr("[-0.5, 0.5] rad/s"));
  EXPECT_THAT(error_of("odometry_bias:bv=0.1"), HasSubstr("did you mean 'b_v'"));
  fx.odometry_bias->b_v = 1.0;
  std::string why;
  EXPECT_FALSE(validate_effects(fx, &why));
  EXPECT_THAT(why, HasSubstr("odometry_bias.b_v = 1"));
  remove_effect(fx, "odometry_bias");
  EXPECT_FALSE(fx.odometry_bias);
}

TEST(ApplyEffect, OverridesOnlyTheGivenParameters) {
  Effects fx;
  apply_effect(fx, parse_effect_spec("radius_error:scale_l=0.995,scale_r=1.004"));
  apply_effect(fx, parse_effect_spec("radius_error:scale_r=1.02"));
  EXPECT_EQ(fx.radius_error->scale_l, 0.995);
  EXPECT_EQ(fx.radius_error->scale_r, 1.02);
  // A required parameter need not be repeated when overriding another one.
  apply_effect(fx, parse_effect_spec("slip_zone:x0=1,x1=2,y0=-1,y1=1,s_l=0.1"));
  apply_effect(fx, parse_effect_spec("slip_zone:s_r=0.3"));
  EXPECT_EQ(fx.slip_zone->x1, 2.0);
  EXPECT_EQ(fx.slip_zone->s_l, 0.1);
  EXPECT_EQ(fx.slip_zone->s_r, 0.3);
  remove_effect(fx, "slip_zone");
  EXPECT_FALSE(fx.slip_zone);
}

TEST(ApplyEffect, RejectsAnEmptySlipZoneBox) {
  Effects fx;
  try {
    apply_effect(fx, parse_effect_spec("slip_zone:x0=2,x1=1,y0=0,y1=1"));
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("x0 = 2"), HasSubstr("x1 = 1"), HasSubstr("x0 < x1")));
  }
  EXPECT_FALSE(fx.slip_zone);
}

TEST(FormatEffects, ListsEveryActiveEffectAndParsesBack) {
  Effects fx;
  EXPECT_EQ(format_effects(fx), "none");
  fx.lateral_skid = Effects::LateralSkid{0.02};
  fx.radius_error = Effects::RadiusError{0.997, 1.003};
  fx.time_offset = Effects::TimeOffset{-0.01};
  const std::string s = format_effects(fx);
  EXPECT_EQ(s, "radius_error:scale_l=0.997,scale_r=1.003; lateral_skid:k=0.02; time_offset:dt=-0.01");
  // Each part parses back to the same numbers.
  Effects back;
  std::stringstream ss(s);
  std::string part;
  while (std::getline(ss, part, ';')) apply_effect(back, parse_effect_spec(part));
  EXPECT_EQ(format_effects(back), s);
  EXPECT_EQ(back.radius_error->scale_r, 1.003);
}

TEST(ValidateEffects, FlagsOutOfRangeStructValues) {
  Effects fx;
  fx.gyro_scale = Effects::GyroScale{7.0};
  std::string why;
  EXPECT_FALSE(validate_effects(fx, &why));
  EXPECT_THAT(why, HasSubstr("gyro_scale.s = 7"));
  fx.gyro_scale->s = 1.01;
  EXPECT_TRUE(validate_effects(fx, &why)) << why;
}

}  // namespace
}  // namespace odotune::sim

// Model terms (odotune/sim/model_terms.h): names in both forms, evaluation, the
// formula, validation, and the simulator applying them (docs/simulator.md step 5a).
#include <odotune/sim/model_terms.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/sim/effects.h>
#include <odotune/sim/simulator.h>

namespace odotune::sim {
namespace {

using ::testing::HasSubstr;

TEST(ModelTerms, NamesReadBackInBothForms) {
  EXPECT_EQ(term_name(TermTarget::v_l, TermBasis::sin_1), "v_l·sin(φ_l)");
  EXPECT_EQ(term_name(TermTarget::v_r, TermBasis::cos_2), "v_r·cos(2φ_r)");
  EXPECT_EQ(term_name(TermTarget::v_r, TermBasis::cos_2, true), "v_r*cos(2*phi_r)");
  EXPECT_EQ(term_name(TermTarget::v_l, TermBasis::turn_speed), "|v·w|");
  EXPECT_EQ(term_name(TermTarget::v_l, TermBasis::accel), "dv_l/dt");
  for (TermTarget t : {TermTarget::v_l, TermTarget::v_r})
    for (TermBasis b : all_term_bases()) {
      EXPECT_EQ(parse_basis(t, term_name(t, b)), b) << term_name(t, b);
      EXPECT_EQ(parse_basis(t, term_name(t, b, true)), b) << term_name(t, b, true);
    }
  EXPECT_EQ(parse_basis(TermTarget::v_l, " v_l * sin( 3 * phi_l ) "), TermBasis::sin_3);
  EXPECT_EQ(parse_target("v_r"), TermTarget::v_r);
  EXPECT_THROW(parse_target("v"), std::invalid_argument);
  try {
    (void)parse_basis(TermTarget::v_l, "v_r*sin(phi_r)");  // the other wheel's angle
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown term 'v_r*sin(phi_r)' for target v_l"));
    EXPECT_THAT(e.what(), HasSubstr("v_l*sin(phi_l)"));
  }
}

TEST(ModelTerms, BasesEvaluateOnTheState) {
  TermState s;
  s.v_l = 0.4, s.v_r = 0.6, s.a_l = 0.2, s.v = 0.5, s.w = -0.5, s.phi_l = 1.1, s.phi_r = 2.0;
  s.x = 3.0, s.y = -1.0, s.t = 10.0;
  EXPECT_DOUBLE_EQ(basis_value(TermTarget::v_l, TermBasis::speed, s), 0.4);
  EXPECT_DOUBLE_EQ(basis_value(TermTarget::v_l, TermBasis::sin_1, s), 0.4 * std::sin(1.1));
  EXPECT_DOUBLE_EQ(basis_value(TermTarget::v_r, TermBasis::cos_3, s), 0.6 * std::cos(6.0));
  EXPECT_DOUBLE_EQ(basis_value(TermTarget::v_r, TermBasis::constant, s), 1.0);
  EXPECT_DOUBLE_EQ(basis_value(TermTarget::v_l, TermBasis::accel, s), 0.2);
  EXPECT_DOUBLE_EQ(basis_value(TermTarget::v_l, TermBasis::turn_speed, s), 0.25);
  EXPECT_DOUBLE_EQ(basis_value(TermTarget::v_r, TermBasis::speed_turn, s), 0.3);
  EXPECT_DOUBLE_EQ(basis_value(TermTarget::v_l, TermBasis::speed_time, s), 4.0);
  EXPECT_DOUBLE_EQ(basis_value(TermTarget::v_r, TermBasis::speed_y, s), -0.6);
  const std::vector<ModelTerm> terms = {{TermTarget::v_l, TermBasis::sin_1, 0.01},
                                        {TermTarget::v_r, TermBasis::constant, 0.003},
                                        {TermTarget::v_l, TermBasis::cos_1, -0.02}};
  EXPECT_DOUBLE_EQ(term_correction(terms, TermTarget::v_l, s), 0.004 * std::sin(1.1) - 0.008 * std::cos(1.1));
  EXPECT_DOUBLE_EQ(term_correction(terms, TermTarget::v_r, s), 0.003);
}

TEST(ModelTerms, FormulaJoinsAHarmonicPairIntoAmplitudeAndPhase) {
  const double a = 0.012, p = 0.4;
  const std::vector<ModelTerm> oor = {{TermTarget::v_l, TermBasis::sin_1, a * std::cos(p)},
                                      {TermTarget::v_l, TermBasis::cos_1, a * std::sin(p)}};
  EXPECT_EQ(term_formula(oor), "v_l,true = v_l·(1 + 0.012·sin(φ_l + 0.40))");
  const std::vector<ModelTerm> mixed = {{TermTarget::v_r, TermBasis::turn_speed, -0.02},
                                        {TermTarget::v_r, TermBasis::sin_2, 0.005},
                                        {TermTarget::v_l, TermBasis::speed, 0.01}};
  EXPECT_EQ(term_formula(mixed),
            "v_l,true = v_l·(1 + 0.01); v_r,true = v_r·(1 + 0.005·sin(2φ_r)) − 0.02·|v·w|");
  EXPECT_EQ(term_formula({}), "");
  EXPECT_EQ(format_terms(oor), fmt::format("v_l += {}*v_l*sin(phi_l); v_l += {}*v_l*cos(phi_l)",
                                           a * std::cos(p), a * std::sin(p)));
}

TEST(ModelTerms, ValidationNamesTheBadTerm) {
  std::string why;
  EXPECT_TRUE(validate_terms({{TermTarget::v_l, TermBasis::sin_1, 0.01}}, &why));
  EXPECT_FALSE(validate_terms({{TermTarget::v_l, TermBasis::sin_1, std::nan("")}}, &why));
  EXPECT_THAT(why, HasSubstr("term 1 (v_l*sin(phi_l) on v_l): coef = nan"));
  EXPECT_FALSE(validate_terms(
      {{TermTarget::v_r, TermBasis::speed, 0.01}, {TermTarget::v_r, TermBasis::speed, 0.02}}, &why));
  EXPECT_THAT(why, HasSubstr("given twice"));
  Scenario sc;
  sc.motion.segments = {Segment{Segment::Kind::stop, 0, 0, 0, 0, 0, 1.0, 0}};
  sc.terms = {{TermTarget::v_l, TermBasis::speed, INFINITY}};
  EXPECT_FALSE(validate_scenario(sc, &why));
  EXPECT_THAT(why, HasSubstr("terms: term 1"));
}

// A straight drive of a few wheel turns with only encoders and ground truth.
Scenario straight_drive() {
  Scenario sc;
  sc.robot.wheel_radius_left_m = sc.robot.wheel_radius_right_m = 0.1;
  sc.robot.wheel_base_m = 0.4;
  Segment go;
  go.kind = Segment::Kind::straight, go.distance_m = 3.0, go.speed_m_s = 0.5;
  sc.motion.segments = {go};
  auto& s = sc.sensors;
  s.commands.enabled = s.gyro.enabled = s.power.enabled = s.ext_velocity.enabled = s.aps.enabled = false;
  s.encoders.rate_hz = s.ground_truth.rate_hz = 100.0;
  s.ground_truth.resolution_m = s.ground_truth.resolution_rad = 0.0;
  return sc;
}

TEST(ModelTerms, SimulatorAppliesAnOutOfRoundWheel) {
  // v_l,true = v_l*(1 + a*sin(phi_l)) with the right wheel as built: the
  // heading is -(1/D) * integral of a*R*omega*sin(phi) dt = -(a*R/D)*(1 - cos(phi_l))
  // whatever the speed profile, phi_l from the encoder.
  Scenario sc = straight_drive();
  const double a = 0.01, R = 0.1, D = 0.4;
  sc.terms = {{TermTarget::v_l, TermBasis::sin_1, a}};
  const tracks::Track tr = simulate(sc);
  ASSERT_TRUE(tr.has(tracks::Col::gt_theta));
  int checked = 0;
  double max_theta = 0.0;
  for (std::size_t i = 0; i < tr.size(); ++i) {
    // The angle counted lies within one tick above the count: take the
    // middle; the slope of the expectation, a*R/D per radian, times half a
    // tick bounds the error.
    const double tick = 2.0 * std::numbers::pi / sc.robot.ticks_per_rev;
    const double phi = (static_cast<double>(tr.ticks_l()[i]) + 0.5) * tick;
    const double expected = -(a * R / D) * (1.0 - std::cos(phi));
    EXPECT_NEAR(tr.col(tracks::Col::gt_theta)[i], expected, (a * R / D) * 0.5 * tick + 1e-7) << "row " << i;
    max_theta = std::max(max_theta, std::abs(tr.col(tracks::Col::gt_theta)[i]));
    ++checked;
  }
  EXPECT_GT(checked, 500);
  EXPECT_NEAR(max_theta, 2.0 * a * R / D, 1e-5);  // the wobble's full swing was reached
  bool listed = false;
  for (const auto& [key, value] : tr.meta().extra)
    if (key == "sim.terms") listed = value == "v_l += 0.01*v_l*sin(phi_l)";
  EXPECT_TRUE(listed);
}

TEST(ModelTerms, ASpeedTermOnBothWheelsIsARadiusScale) {
  Scenario with_terms = straight_drive(), with_effect = straight_drive();
  with_terms.terms = {{TermTarget::v_l, TermBasis::speed, 0.01}, {TermTarget::v_r, TermBasis::speed, 0.01}};
  apply_effect(with_effect.effects, parse_effect_spec("radius_error:scale_l=1.01,scale_r=1.01"));
  const tracks::Track a = simulate(with_terms), b = simulate(with_effect);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a.col(tracks::Col::gt_x)[i], b.col(tracks::Col::gt_x)[i], 1e-12);
    EXPECT_EQ(a.ticks_l()[i], b.ticks_l()[i]);
  }
  EXPECT_NEAR(a.col(tracks::Col::gt_x).back(), 3.03, 1e-9);
}

}  // namespace
}  // namespace odotune::sim

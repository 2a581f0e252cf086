// Plausibility of a fitted calibration (odotune/calibration/plausible_fit.h): within
// a factor of 2 of the nominal geometry, or of the identity for a twist's
// scales, at both edges and beyond, and the first implausible value named.
#include <cmath>
#include <limits>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/calibration/plausible_fit.h>

namespace odotune::calibration {
namespace {

using ::testing::HasSubstr;
using filters::OdometryParams;
using filters::TwistCorrection;

const OdometryParams kNominal{0.041, 0.041, 0.20};

TEST(PlausibleFit, AGeometryWithinAFactorOfTwoOfTheNominalIsPlausible) {
  EXPECT_FALSE(implausible_geometry(kNominal, kNominal));
  EXPECT_FALSE(implausible_geometry({0.041 * 0.5, 0.041 * 2.0, 0.20 * 1.07}, kNominal));
}

TEST(PlausibleFit, APathShrunkTowardsAPointIsNamedByItsFirstValue) {
  // The σ 1 m fit of OptiOdom's three 2-3 Jan runs (docs/robot-localization.md).
  const auto why = implausible_geometry({0.00042, 0.03472, 0.46594}, kNominal);
  ASSERT_TRUE(why);
  EXPECT_THAT(*why,
              HasSubstr("wheel_radius_left_m = 0.00042 m is 0.0102 × the nominal 0.041 m (expected 0.5–2 ×)"));
  const auto base = implausible_geometry({0.041, 0.041, 0.41}, kNominal);
  ASSERT_TRUE(base);
  EXPECT_THAT(*base, HasSubstr("wheel_base_m = 0.41 m is 2.05 × the nominal 0.2 m"));
  EXPECT_TRUE(implausible_geometry({0.041, 0.041, std::numeric_limits<double>::quiet_NaN()}, kNominal));
}

TEST(PlausibleFit, ATwistsScalesAreJudgedAgainstTheIdentityAndItsDelayIsNot) {
  EXPECT_FALSE(implausible_twist({0.95, 1.34, 0.58}));
  EXPECT_FALSE(implausible_twist({0.5, 2.0, 0.0}));
  const auto why = implausible_twist({1.0, 0.3, 0.0});
  ASSERT_TRUE(why);
  EXPECT_THAT(*why, HasSubstr("scale_w = 0.3 is 0.3 × the nominal 1"));
  EXPECT_TRUE(implausible_twist({2.5, 1.0, 0.0}));
}

TEST(PlausibleFit, TheRefusalIsOneLineThatSaysNothingWasWritten) {
  const std::string m = implausible_fit_message("scale_w = 0.3 is 0.3 × the nominal 1 (expected 0.5–2 ×)");
  EXPECT_EQ(m.find('\n'), std::string::npos);
  EXPECT_THAT(m, HasSubstr("calibrate: the fit is not one this robot can have: scale_w = 0.3"));
  EXPECT_THAT(m, HasSubstr("nothing was written"));
}

}  // namespace
}  // namespace odotune::calibration

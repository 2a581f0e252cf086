// The fitness modes: numbers and names both ways, what the command line and
// experiment files accept, and that each mode's scalar is the one it names.
#include <odotune/objectives/fitness_mode.h>

#include <stdexcept>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/objectives/fix_cv_replay.h>
#include <odotune/objectives/metrics.h>

namespace odotune::objectives {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

TEST(FitnessMode, NumbersAndKeysRoundTrip) {
  int expected = 1;
  for (FitnessMode m : kAllFitnessModes) {
    EXPECT_EQ(number(m), expected++);
    EXPECT_EQ(fitness_mode_of_number(number(m)), m);
    FitnessMode parsed{};
    ASSERT_TRUE(parse_fitness_mode(std::to_string(number(m)), &parsed));
    EXPECT_EQ(parsed, m);
    ASSERT_TRUE(parse_fitness_mode(fitness_mode_key(m), &parsed)) << fitness_mode_key(m);
    EXPECT_EQ(parsed, m);
  }
  EXPECT_EQ(fitness_mode_name(FitnessMode::rmse_mae), "RMSE+MAE");
  EXPECT_EQ(fitness_mode_name(FitnessMode::fix_nll), "held-out fix NLL");
  EXPECT_EQ(ground_truth_mode_numbers(), (std::vector<int>{1, 2, 3, 4, 5, 6, 7}));
}

TEST(FitnessMode, RefusesWhatIsNotAMode) {
  FitnessMode m = FitnessMode::mae;
  for (const char* bad : {"0", "10", "-1", "7.0", "", "RMSE", "rmse ", "fix_rmse", "7x"}) {
    EXPECT_FALSE(parse_fitness_mode(bad, &m)) << bad;
    EXPECT_EQ(m, FitnessMode::mae) << "unchanged on failure: " << bad;
  }
  EXPECT_FALSE(fitness_mode_of_number(0).has_value());
  EXPECT_FALSE(fitness_mode_of_number(10).has_value());
  EXPECT_THAT(fitness_mode_choices(), StartsWith("1..9 or rmse, mae, maxe"));
  EXPECT_THAT(fitness_mode_choices(), HasSubstr("fix-nll"));
  EXPECT_THAT(fitness_mode_choices(true), StartsWith("1..7 or rmse"));
  EXPECT_THAT(fitness_mode_choices(true), ::testing::Not(HasSubstr("fix-")));
}

TEST(FitnessMode, GroundTruthAndFixModesScoreTheirOwnScalars) {
  for (FitnessMode m : kGroundTruthModes) EXPECT_FALSE(is_fix_cv(m));
  EXPECT_TRUE(is_fix_cv(FitnessMode::fix_rmse));
  EXPECT_TRUE(is_fix_cv(FitnessMode::fix_nll));
  const ErrorMetrics e{0.1, 0.2, 0.4, 3};
  EXPECT_THROW(fitness_of(e, FitnessMode::fix_rmse), std::logic_error);
  FixCvOutcome o;
  o.heldout.rmse_m = 0.25;
  o.nll = -1.5;
  EXPECT_EQ(fix_cv_fitness(o, FitnessMode::fix_rmse), 0.25);
  EXPECT_EQ(fix_cv_fitness(o, FitnessMode::fix_nll), -1.5);
  EXPECT_THROW(fix_cv_fitness(o, FitnessMode::rmse), std::logic_error);
}

}  // namespace
}  // namespace odotune::objectives

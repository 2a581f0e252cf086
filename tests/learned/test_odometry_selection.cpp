// The choice of correction nets by cross-validation
// (odotune/learned/odometry_selection.h): the gate on every fold and the
// one-standard-error rule, on measures written by hand.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/learned/odometry_selection.h>

namespace odotune::learned {
namespace {

// A fold where the nets take the given fractions of the kinematic MAEs, and
// each combination its pose ratio (kinematic 1 m at every measure).
FoldMeasures selection_fold(double v_ratio, double w_ratio, double v_pose, double w_pose, double both_pose) {
  FoldMeasures f;
  f.v_mae = {0.01, 0.01 * v_ratio};
  f.w_mae = {0.1, 0.1 * w_ratio};
  const double ratio[kNetCombinations] = {1.0, v_pose, w_pose, both_pose};
  for (int c = 0; c < kNetCombinations; ++c)
    f.pose_rmse[static_cast<std::size_t>(c)] = {ratio[c], ratio[c], ratio[c]};
  return f;
}

CandidateResult selection_candidate(CorrectionSettings s, std::vector<FoldMeasures> folds) {
  CandidateResult r;
  r.settings = s;
  r.folds = std::move(folds);
  score_candidate(r);
  return r;
}

TEST(OdometrySelection, ACombinationQualifiesOnlyWhenEveryFoldGains) {
  const CandidateResult r = selection_candidate({}, {selection_fold(0.8, 0.9, 0.9, 0.7, 0.6),
                                                     selection_fold(0.8, 1.01, 0.95, 1.2, 0.8)});
  EXPECT_TRUE(r.qualifies[0]);   // the kinematics always do
  EXPECT_TRUE(r.qualifies[1]);   // V net: lower V MAE and pose on both folds
  EXPECT_FALSE(r.qualifies[2]);  // W net: W MAE higher on fold 2, its pose worse there
  EXPECT_FALSE(r.qualifies[3]);  // both: uses the W net, whose MAE is higher on fold 2
  EXPECT_NEAR(r.score[1], 0.5 * (std::log(0.9) + std::log(0.95)), 1e-12);
  EXPECT_NEAR(r.score_se[1], std::abs(std::log(0.9) - std::log(0.95)) / 2.0, 1e-12);
  EXPECT_EQ(r.score[0], 0.0);
  // A whole unit worse on one fold disqualifies, whatever the mean.
  FoldMeasures worse = selection_fold(0.5, 0.5, 0.5, 0.5, 0.5);
  worse.pose_rmse[3][2] = 1.01;
  EXPECT_FALSE(selection_candidate({}, {selection_fold(0.5, 0.5, 0.5, 0.5, 0.3), worse}).qualifies[3]);
}

TEST(OdometrySelection, TheSimplestWithinOneStandardErrorIsChosen) {
  SelectionSummary s;
  CorrectionSettings simple{3, 10, 10.0, LearnedFeatures::channel};
  CorrectionSettings complex{5, 20, 0.0, LearnedFeatures::both};
  // The complex candidate scores best, the simple one within its standard error.
  s.candidates.push_back(selection_candidate(complex, {selection_fold(0.9, 0.9, 0.9, 0.9, 0.55),
                                                       selection_fold(0.9, 0.9, 0.9, 0.9, 0.75)}));
  s.candidates.push_back(selection_candidate(simple, {selection_fold(0.9, 0.9, 0.9, 0.9, 0.65),
                                                      selection_fold(0.9, 0.9, 0.9, 0.9, 0.7)}));
  choose_candidate(s);
  EXPECT_EQ(s.chosen, 1u);
  EXPECT_EQ(s.combination, NetCombination::both);
  // Far better (beyond one standard error): the complex one.
  s.candidates[0] = selection_candidate(complex, {selection_fold(0.9, 0.9, 0.9, 0.9, 0.3),
                                                  selection_fold(0.9, 0.9, 0.9, 0.9, 0.32)});
  choose_candidate(s);
  EXPECT_EQ(s.chosen, 0u);
}

TEST(OdometrySelection, NothingQualifyingMeansTheKinematics) {
  SelectionSummary s;
  s.candidates.push_back(selection_candidate({}, {selection_fold(1.1, 1.1, 1.2, 1.1, 1.3),
                                                  selection_fold(0.9, 0.9, 0.8, 0.9, 0.9)}));
  s.candidates.push_back(
      selection_candidate({3, 10, 0.0, LearnedFeatures::channel},
                          {selection_fold(1.1, 1.1, 1.1, 1.1, 1.1), selection_fold(0.9, 1.2, 0.95, 1.3, 1.4)}));
  choose_candidate(s);
  EXPECT_EQ(s.combination, NetCombination::kinematic);
  EXPECT_EQ(s.chosen, 0u);  // the best score, for the report
}

TEST(OdometrySelection, OptionsAreCheckedByName) {
  std::string why;
  SelectionOptions o;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.units = {4};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("units 4"), std::string::npos) << why;
  o = {};
  o.features = {LearnedFeatures::paper};
  EXPECT_FALSE(o.IsValid(&why));
  o = {};
  o.training.early_stopping_patience = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("early_stopping_patience"), std::string::npos) << why;
}

}  // namespace
}  // namespace odotune::learned

// The UKF as a tunable model (odotune/learned/ukf_objective.h): its named,
// bounded, log-scaled space, the fitness against a direct replay, PSO
// lowering the fitness below the defaults' on a track with a radius error,
// determinism over seeds and thread counts, divergence as a counted penalty,
// and the one-line errors.
#include <cmath>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <omp.h>

#include <odotune/learned/fusion_input.h>
#include <odotune/learned/ukf_objective.h>
#include <odotune/objectives/ekf_objective.h>  // kDivergencePenalty
#include <odotune/tuner/pso.h>

#include "support/fusion_track.h"

namespace odotune::learned {
namespace {

using testing_support::fusion_track;
using testing_support::FusionTrackOptions;

// A 2 % smaller right tyre and a gyro with a bias: the defaults (odometry
// variance 1e-3, gyro variance 4e-6) trust the biased sensors too much.
const FusionInput& biased_input() {
  static const FusionInput in = [] {
    FusionTrackOptions o;
    o.name = "biased";
    o.seed = 11;
    o.effects = {"radius_error:scale_l=1.0,scale_r=0.98", "gyro_bias:b=0.01"};
    return build_fusion_input(fusion_track(o));
  }();
  return in;
}

TEST(UkfSpace, NamedBoundedLogScaledAroundTheDefaults) {
  const objectives::BoxSpace space = ukf_space();
  ASSERT_EQ(space.dim(), 6u);
  const std::vector<std::string> names = {"q_v_m2_s3", "q_w_rad2_s3", "odo_var_v",
                                          "odo_var_w", "gyro_var",    "ext_var_scale"};
  const std::vector<double> defaults = ukf_params_of(UkfSettings{});
  for (std::size_t i = 0; i < names.size(); ++i) {
    const objectives::ParamSpec& p = space.params()[i];
    EXPECT_EQ(p.name, names[i]);
    EXPECT_TRUE(p.log_scale) << p.name;
    EXPECT_GE(std::log10(p.upper / p.lower), 4.0) << p.name << ": spans decades";
    // The defaults lie well inside (≥ a decade from either bound).
    EXPECT_GE(defaults[i] / p.lower, 10.0) << p.name;
    EXPECT_GE(p.upper / defaults[i], 10.0) << p.name;
  }
  EXPECT_EQ(defaults[0], filters::UkfParams{}.q_v_m2_s3);
  EXPECT_EQ(defaults[4], UkfSensorNoise{}.gyro_var);

  const std::vector<double> v = {0.01, 0.02, 3e-4, 4e-4, 5e-6, 2.0};
  const UkfSettings s = apply_ukf_params(UkfSettings{}, v);
  EXPECT_EQ(s.params.q_w_rad2_s3, 0.02);
  EXPECT_EQ(s.odo_var_v, 3e-4);
  EXPECT_EQ(s.noise.ext_var_scale, 2.0);
  EXPECT_EQ(ukf_params_of(s), v);
  EXPECT_THROW(apply_ukf_params(UkfSettings{}, std::vector<double>(5, 1.0)), std::invalid_argument);
}

TEST(UkfObjective, FitnessIsTheModeOfTheReplaysErrors) {
  const FusionInput& in = biased_input();
  const UkfObjective obj({&in}, objectives::FitnessMode::rmse);
  const UkfSettings defaults;
  const std::vector<double> x = ukf_space().to_box(ukf_params_of(defaults));
  bool healthy = false;
  const objectives::ErrorMetrics e = ukf_pose_errors(in, defaults, &healthy);
  ASSERT_TRUE(healthy);
  EXPECT_GT(e.samples, 100);
  EXPECT_NEAR(obj.fitness(x), e.rmse_m, 1e-12 * e.rmse_m);
  const UkfObjective obj7({&in, &in}, objectives::FitnessMode::rmse_mae_maxe);
  EXPECT_NEAR(obj7.fitness(x), e.rmse_m + e.mae_m + e.maxe_m, 1e-12);  // mean of two equal tracks
  EXPECT_EQ(obj.evaluations(), 1);
  EXPECT_EQ(obj.failures(), 0);
}

// The objective as the tuner sees it (objectives/ does not depend on tuner/;
// the CLI has the same adapter).
struct BoxProblem {
  const UkfObjective* objective;
  double fitness(std::span<const double> x) const { return objective->fitness(x); }
  tuner::Bounds bounds() const {
    auto [lo, hi] = objective->bounds();
    return {lo, hi};
  }
};

tuner::Summary small_pso(const UkfObjective& obj, std::uint64_t seed) {
  tuner::PsoOptions o;
  o.particles = 12;
  o.iterations = 10;
  o.seed = seed;
  return tuner::pso_minimize(BoxProblem{&obj}, o);
}

TEST(UkfObjective, PsoBeatsTheDefaultsAndIsDeterministic) {
  const FusionInput& in = biased_input();
  const UkfObjective obj({&in}, objectives::FitnessMode::rmse);
  const double at_defaults = obj.fitness(ukf_space().to_box(ukf_params_of(UkfSettings{})));

  const int threads_before = omp_get_max_threads();
  omp_set_num_threads(1);
  const tuner::Summary one = small_pso(obj, 3);
  omp_set_num_threads(2);
  const tuner::Summary two = small_pso(obj, 3);
  omp_set_num_threads(threads_before);
  EXPECT_LT(one.best_fitness, 0.8 * at_defaults) << one.best_fitness << " vs defaults " << at_defaults;
  EXPECT_EQ(one.best_x, two.best_x);  // bit-identical for any thread count
  EXPECT_EQ(one.best_fitness, two.best_fitness);
  EXPECT_EQ(obj.failures(), 0);

  // The tuned settings replay to the fitness the solver reported.
  const UkfSettings tuned = obj.settings_at(one.best_x);
  EXPECT_EQ(ukf_pose_errors(in, tuned).rmse_m, one.best_fitness);
}

TEST(UkfObjective, DivergenceIsACountedPenalty) {
  FusionInput broken = biased_input();
  broken.v_kin[30] = std::nan("");  // the odometry breaks mid-way: the filter turns unhealthy
  const UkfObjective obj({&broken}, objectives::FitnessMode::rmse);
  const std::vector<double> x = ukf_space().to_box(ukf_params_of(UkfSettings{}));
  EXPECT_EQ(obj.fitness(x), objectives::kDivergencePenalty);
  EXPECT_EQ(obj.failures(), 1);
  // A non-finite box coordinate: a penalty too, never an exception.
  std::vector<double> bad = x;
  bad[2] = std::nan("");
  EXPECT_EQ(obj.fitness(bad), objectives::kDivergencePenalty);
  EXPECT_EQ(obj.failures(), 2);
  EXPECT_EQ(obj.evaluations(), 2);
}

TEST(UkfObjective, OneLineErrors) {
  FusionTrackOptions o;
  o.name = "no_truth";
  o.gt = false;
  const FusionInput no_gt = build_fusion_input(fusion_track(o));
  try {
    UkfObjective obj({&no_gt}, objectives::FitnessMode::rmse);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("track 'no_truth': no ground truth"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
  EXPECT_THROW(UkfObjective({&biased_input()}, objectives::FitnessMode::fix_rmse), std::invalid_argument);
  EXPECT_THROW(UkfObjective({}, objectives::FitnessMode::rmse), std::invalid_argument);
  UkfSettings bad;
  bad.odo_var_w = 0.0;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("odo_var_w = 0"), std::string::npos) << why;
}

}  // namespace
}  // namespace odotune::learned

// Velocity fusion (odotune/learned/ukf_fusion.h) on small simulated drives
// (fusion_track.h): the UKF's consistency (NEES within χ² bounds on a clean
// track, and a mis-set filter failing the same bounds), fusion with the
// external velocities beating the odometry alone under a radius error, the
// pose integration and the trace's bookkeeping, and bad input.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/filters/velocity_ukf.h>
#include <odotune/learned/fusion_input.h>
#include <odotune/learned/ukf_fusion.h>

#include "support/fusion_track.h"

namespace odotune::learned {
namespace {

using testing_support::fusion_track;
using testing_support::FusionTrackOptions;

// ---------------------------------------------------------------------------
// Consistency (NEES, paper eq. 10 per step; Bar-Shalom, Li & Kirubarajan,
// "Estimation with Applications to Tracking and Navigation", §5.4).
//
// The clean track: the drive of fusion_track.h with no effect, coarse
// encoders (256 counts/rev, so the odometry is not overwhelmingly precise and
// the three sensors all weigh in), a gyro of σ 0.02 rad/s and gentle
// acceleration limits (0.2 m/s², 0.5 rad/s²).
//
// Filter settings, each from the simulator's actual noise (simulator.h):
//  * odometry: the encoders floor-quantise the rotation; a step's increment
//    is off by the difference of two independent uniform [0, 1) count
//    errors, variance 1/6 count² per wheel. With c = 2πR/(N·Δt) the speed
//    of one count per step, V = c(n_l + n_r)/2 and W = c(n_r − n_l)/D give
//      var_v = c²/12,   var_w = c²/(3 D²).
//  * external velocity: σ 0.02 m/s and 0.02 rad/s, i.e. the track's own
//    v_ext_var / w_ext_var (ext_var_scale = 1).
//  * gyro: the step's value is the mean of 10 samples of σ_g:
//      gyro_var = σ_g²/10.
//  * process noise: the filter's random walk has increments of variance
//    q·Δt; the truth's step means change by a·Δt on the acceleration ramps
//    (0 elsewhere), so matching one step of the steepest ramp,
//      q_v = a_max²·Δt,   q_w = α_max²·Δt.
// The truth is the ground truth's mean velocity over each step (v_true,
// w_true), what the odometry and the gyro measure.
struct CleanSetup {
  double tpr = 256.0, radius = 0.08, base = 0.42, dt = 0.1;
  double gyro_sigma = 0.02, a_max = 0.2, alpha_max = 0.5;
  double c() const { return 2.0 * std::numbers::pi * radius / (tpr * dt); }
  double var_v() const { return c() * c() / 12.0; }
  double var_w() const { return c() * c() / (3.0 * base * base); }
  filters::UkfParams params() const {
    filters::UkfParams p;
    p.q_v_m2_s3 = a_max * a_max * dt;
    p.q_w_rad2_s3 = alpha_max * alpha_max * dt;
    return p;
  }
  UkfSensorNoise noise() const {
    UkfSensorNoise n;
    n.gyro_var = gyro_sigma * gyro_sigma / 10.0;
    n.ext_var_scale = 1.0;
    return n;
  }
  FusionTrackOptions track(std::uint64_t seed) const {
    FusionTrackOptions o;
    o.seed = seed;
    o.ticks_per_rev = tpr;
    o.gyro_sigma_rad_s = gyro_sigma;
    o.max_accel_m_s2 = a_max;
    o.max_angular_accel_rad_s2 = alpha_max;
    o.power = false;
    return o;
  }
};

struct NeesRuns {
  std::vector<std::vector<double>> per_run;  // NEES_k per run (steps k ≥ 1)
};

std::vector<FusionInput> clean_inputs(const CleanSetup& s, int runs) {
  std::vector<FusionInput> v;
  for (int m = 0; m < runs; ++m)
    v.push_back(build_fusion_input(fusion_track(s.track(static_cast<std::uint64_t>(101 + m)))));
  return v;
}

NeesRuns nees_runs(const std::vector<FusionInput>& inputs, double var_v, double var_w,
                   const filters::UkfParams& params, const UkfSensorNoise& noise) {
  NeesRuns out;
  for (const FusionInput& in : inputs) {
    const FusionTrace tr = replay_fusion(in, static_odometry(in, var_v, var_w), params, noise);
    EXPECT_TRUE(tr.healthy);
    std::vector<double> e;
    for (std::size_t k = 1; k < in.size(); ++k) {
      filters::VelocityCov P;
      P << tr.var_v[k], tr.cov_vw[k], tr.cov_vw[k], tr.var_w[k];
      e.push_back(filters::nees(filters::Velocity(in.v_true[k], in.w_true[k]),
                                filters::Velocity(tr.v[k], tr.w[k]), P));
    }
    out.per_run.push_back(std::move(e));
  }
  return out;
}

// Two criteria, both at the effective sample count n_eff below:
//  * the mean NEES over all steps and runs lies in its two-sided 99 %
//    interval (n_eff independent χ²₂ samples: the sum is χ²(2·n_eff));
//  * the fraction of per-step NEES below χ²₂(0.95) = 5.99 is at least
//    0.95 − 3·√(0.95·0.05/n_eff) (the binomial's 3σ lower bound; 0.904 here).
struct NeesVerdict {
  double mean = 0.0;          // time- and run-averaged NEES
  double lo = 0.0, hi = 0.0;  // its two-sided 99 % χ² interval
  double below_95 = 0.0;      // fraction of per-step NEES below χ²₂(0.95)
  double min_below = 0.0;     // the lowest acceptable fraction
  bool consistent() const { return mean >= lo && mean <= hi && below_95 >= min_below; }
};

// Effective number of independent NEES samples per run: one per kDecorrSteps
// steps. Consecutive steps share the encoder count error at their common end
// (the odometry errors are MA(1)), and the model's mismatch on a ramp (the
// ramps last 0.8–2.5 s here) errs the same way for its whole length; one
// independent sample per second (10 steps) is what the track can justify.
constexpr std::size_t kDecorrSteps = 10;

// The standard normal's 99.5 % quantile.
constexpr double kZ995 = 2.5758293035489004;

// χ²_ν quantile at the normal quantile z, Wilson & Hilferty (1931):
// ν(1 − 2/(9ν) + z·√(2/(9ν)))³; relative error < 1e-3 for ν ≥ 30 (we use
// ν > 100).
double chi2_quantile(double nu, double z) {
  const double a = 2.0 / (9.0 * nu);
  return nu * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}

NeesVerdict verdict(const NeesRuns& r) {
  double sum = 0.0;
  std::size_t n = 0, below = 0;
  const double chi2_95 = -2.0 * std::log(0.05);  // χ²₂ quantile: exp(−x/2) tail; 5.99
  for (const auto& run : r.per_run)
    for (double x : run) {
      sum += x;
      ++n;
      if (x <= chi2_95) ++below;
    }
  NeesVerdict v;
  v.mean = sum / static_cast<double>(n);
  v.below_95 = static_cast<double>(below) / static_cast<double>(n);
  // n_eff independent χ²₂ samples: their sum is χ²(2·n_eff); the mean's 99 %
  // interval is [χ²(2n_eff; 0.005), χ²(2n_eff; 0.995)] / n_eff.
  double n_eff = 0.0;
  for (const auto& run : r.per_run) n_eff += std::floor(static_cast<double>(run.size()) / kDecorrSteps);
  v.lo = chi2_quantile(2.0 * n_eff, -kZ995) / n_eff;
  v.hi = chi2_quantile(2.0 * n_eff, kZ995) / n_eff;
  v.min_below = 0.95 - 3.0 * std::sqrt(0.95 * 0.05 / n_eff);
  return v;
}

class UkfConsistency : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { inputs_ = new std::vector<FusionInput>(clean_inputs(CleanSetup{}, 12)); }
  static void TearDownTestSuite() {
    delete inputs_;
    inputs_ = nullptr;
  }
  static std::vector<FusionInput>* inputs_;
};
std::vector<FusionInput>* UkfConsistency::inputs_ = nullptr;

TEST_F(UkfConsistency, NeesWithinChiSquareBoundsOnACleanTrack) {
  const CleanSetup s;
  const NeesVerdict v = verdict(nees_runs(*inputs_, s.var_v(), s.var_w(), s.params(), s.noise()));
  EXPECT_TRUE(v.consistent()) << "mean NEES " << v.mean << " (99 % interval [" << v.lo << ", " << v.hi << "]), "
                              << 100.0 * v.below_95 << " % below 5.99 (at least " << 100.0 * v.min_below
                              << " % expected)";
}

TEST_F(UkfConsistency, ProcessNoiseFarTooSmallFails) {
  const CleanSetup s;
  filters::UkfParams p = s.params();
  p.q_v_m2_s3 /= 1000.0;
  p.q_w_rad2_s3 /= 1000.0;
  const NeesVerdict v = verdict(nees_runs(*inputs_, s.var_v(), s.var_w(), p, s.noise()));
  EXPECT_FALSE(v.consistent()) << "mean NEES " << v.mean << " (99 % interval [" << v.lo << ", " << v.hi
                               << "]), " << 100.0 * v.below_95 << " % below 5.99";
  EXPECT_GT(v.mean, v.hi);
}

TEST_F(UkfConsistency, MeasurementVariancesFarTooSmallFail) {
  const CleanSetup s;
  UkfSensorNoise n = s.noise();
  n.gyro_var /= 100.0;
  n.ext_var_scale /= 100.0;
  const NeesVerdict v = verdict(nees_runs(*inputs_, s.var_v() / 100.0, s.var_w() / 100.0, s.params(), n));
  EXPECT_FALSE(v.consistent()) << "mean NEES " << v.mean;
  EXPECT_GT(v.mean, v.hi);
  EXPECT_LT(v.below_95, v.min_below);
}

TEST_F(UkfConsistency, MeasurementVariancesFarTooLargeFail) {
  // The opposite mistake: a filter that trusts nothing is also inconsistent
  // (NEES far below its expectation of 2).
  const CleanSetup s;
  UkfSensorNoise n = s.noise();
  n.gyro_var *= 100.0;
  n.ext_var_scale *= 100.0;
  filters::UkfParams p = s.params();
  p.q_v_m2_s3 *= 100.0;
  p.q_w_rad2_s3 *= 100.0;
  const NeesVerdict v = verdict(nees_runs(*inputs_, s.var_v() * 100.0, s.var_w() * 100.0, p, n));
  EXPECT_FALSE(v.consistent()) << "mean NEES " << v.mean;
  EXPECT_LT(v.mean, v.lo);
}

// ---------------------------------------------------------------------------

TEST(UkfFusion, ExternalVelocitiesBeatOdometryAloneUnderARadiusError) {
  // A 2 % smaller right tyre: the nominal odometry curves the wrong way; the
  // lidar's unbiased (V, W) pull the fused estimate back.
  FusionTrackOptions o;
  o.seed = 5;
  o.laps = 2;
  o.gyro = false;
  o.effects = {"radius_error:scale_l=1.0,scale_r=0.98"};
  const FusionInput in = build_fusion_input(fusion_track(o));
  const auto odo = static_odometry(in, 1e-4, 1e-3);
  filters::UkfParams p;
  p.q_v_m2_s3 = 4e-3;
  p.q_w_rad2_s3 = 2.5e-2;
  UkfSensorNoise with_ext, without_ext;
  without_ext.use_external = false;
  const FusionTrace fused = replay_fusion(in, odo, p, with_ext);
  const FusionTrace odo_only = replay_fusion(in, odo, p, without_ext);
  ASSERT_TRUE(fused.healthy && odo_only.healthy);
  const objectives::ErrorMetrics e_fused = fusion_pose_errors(in, fused);
  const objectives::ErrorMetrics e_odo = fusion_pose_errors(in, odo_only);
  EXPECT_EQ(e_fused.samples, static_cast<long>(in.size()) - 1);
  EXPECT_GT(e_odo.rmse_m, 0.05);  // the radius error shows
  EXPECT_LT(e_fused.rmse_m, 0.5 * e_odo.rmse_m) << e_fused.rmse_m << " vs " << e_odo.rmse_m;
}

TEST(UkfFusion, TraceStartsAtTheGroundTruthAndIntegratesEq3) {
  const FusionInput in = build_fusion_input(fusion_track(FusionTrackOptions{}));
  const auto odo = static_odometry(in, 1e-5, 1e-4);
  const FusionTrace tr = replay_fusion(in, odo, filters::UkfParams{}, UkfSensorNoise{});
  ASSERT_TRUE(tr.healthy);
  ASSERT_EQ(tr.x.size(), in.size());
  EXPECT_EQ(tr.x[0], in.gt_x[0]);
  EXPECT_EQ(tr.y[0], in.gt_y[0]);
  EXPECT_EQ(tr.theta[0], in.gt_theta[0]);
  EXPECT_EQ(tr.v[0], 0.0);  // UkfParams' initial state: at rest
  for (std::size_t k = 1; k < in.size(); ++k) {
    const filters::PlanarPose next = filters::integrate_pose({tr.x[k - 1], tr.y[k - 1], tr.theta[k - 1]},
                                                             tr.v[k], tr.w[k], in.dt_s);
    ASSERT_DOUBLE_EQ(tr.x[k], next.x_m);
    ASSERT_DOUBLE_EQ(tr.theta[k], next.theta_rad);
    ASSERT_GT(tr.var_v[k], 0.0);
    ASSERT_GT(tr.var_w[k], 0.0);
  }
  // Clean track, precise odometry: the fused pose ends close to the truth.
  const objectives::ErrorMetrics e = fusion_pose_errors(in, tr);
  EXPECT_LT(e.maxe_m, 0.05);
  EXPECT_LE(e.mae_m, e.rmse_m);
  EXPECT_LE(e.rmse_m, e.maxe_m);

  // The odometry's variances matter: a stepwise measurement with huge
  // variance leaves the estimate to the other sensors.
  EXPECT_EQ(static_odometry(in, 2e-3, 3e-3)[7].var_w, 3e-3);
  EXPECT_EQ(static_odometry(in, 2e-3, 3e-3)[7].v_m_s, in.v_kin[7]);
}

TEST(UkfFusion, NonFiniteOdometryMakesTheTraceUnhealthy) {
  const FusionInput in = build_fusion_input(fusion_track(FusionTrackOptions{}));
  auto odo = static_odometry(in, 1e-4, 1e-4);
  odo[20].w_rad_s = std::nan("");
  const FusionTrace tr = replay_fusion(in, odo, filters::UkfParams{}, UkfSensorNoise{});
  EXPECT_FALSE(tr.healthy);
  EXPECT_TRUE(std::isfinite(tr.x[19]));
  EXPECT_TRUE(std::isnan(tr.x[20]));
  EXPECT_TRUE(std::isnan(fusion_pose_errors(in, tr).rmse_m));
}

TEST(UkfFusion, BadInputThrowsNamingTheValue) {
  const FusionInput in = build_fusion_input(fusion_track(FusionTrackOptions{}));
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(message([&] { static_odometry(in, 0.0, 1e-3); }).find("var_v = 0"), std::string::npos);
  EXPECT_NE(message([&] { static_odometry(in, 1e-3, -1.0); }).find("var_w = -1"), std::string::npos);
  const auto odo = static_odometry(in, 1e-4, 1e-4);
  UkfSensorNoise n;
  n.gyro_var = 0.0;
  EXPECT_NE(message([&] { replay_fusion(in, odo, {}, n); }).find("gyro_var = 0"), std::string::npos);
  n = {};
  n.ext_var_scale = std::nan("");
  EXPECT_NE(message([&] { replay_fusion(in, odo, {}, n); }).find("ext_var_scale"), std::string::npos);
  filters::UkfParams p;
  p.q_v_m2_s3 = -1.0;
  EXPECT_NE(message([&] { replay_fusion(in, odo, p, {}); }).find("q_v_m2_s3 = -1"), std::string::npos);
  const std::vector<OdometryMeasurement> short_odo(3);
  EXPECT_NE(message([&] { replay_fusion(in, short_odo, {}, {}); }).find("track 'fusion'"), std::string::npos);
}

}  // namespace
}  // namespace odotune::learned

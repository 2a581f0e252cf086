// The velocity-fusion UKF as a tunable model: its noise
// parameters (the process-noise rates of V and W, the static variances of
// the kinematic odometry, the gyro's variance and a scale on the external
// velocities' variances) form a named, bounded, log-scaled space that `tune`
// and `grid` search like the EKF noise models; the objective replays the
// fusion of Fariña et al., "Improving Odometric Model Performance Based on
// LSTM Networks", Sensors 2023, 23, 961 (../shared/papers/002_*.txt, §1)
// over tracks with ground truth (ukf_fusion.h) and scores the integrated
// pose (eq. 3) by one of the seven fitness modes (metrics.h).
//
// A plain struct in the pagmo2 sense: `fitness(x) const` and `bounds()`; the
// optimiser sees the box, never the filter. Several tracks: the mean of the
// per-track fitness values. A replay whose filter turns unhealthy (non-finite
// state, covariance not positive definite) or whose metrics are not finite
// scores kDivergencePenalty (ekf_objective.h) and is counted in failures();
// nothing is thrown.
#pragma once

#include <atomic>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <odotune/filters/velocity_ukf.h>
#include <odotune/learned/fusion_input.h>
#include <odotune/learned/ukf_fusion.h>
#include <odotune/objectives/box_space.h>
#include <odotune/objectives/metrics.h>

namespace odotune::learned {

// Everything a fusion replay needs besides the input: the filter's
// parameters, the sensors' noise and the odometry's static variances.
struct UkfSettings {
  filters::UkfParams params;  // q_v, q_w (+ the fixed UT parameters, initial state)
  UkfSensorNoise noise;       // gyro_var, ext_var_scale, sensors used
  double odo_var_v = 1e-3;    // static variance of the kinematic V [(m/s)²]
  double odo_var_w = 1e-3;    // static variance of the kinematic W [(rad/s)²]
  // params and noise valid, odometry variances finite and > 0; `why` names
  // the bad value.
  bool IsValid(std::string* why) const;
};

// The tuned values, in this order and in these units (all log-scaled):
//   q_v_m2_s3 [(m/s)²/s], q_w_rad2_s3 [(rad/s)²/s], odo_var_v [(m/s)²],
//   odo_var_w [(rad/s)²], gyro_var [(rad/s)²], ext_var_scale [-].
objectives::BoxSpace ukf_space();
// Physical values (ukf_space() order and units) applied to `base`. Throws
// std::invalid_argument on a wrong dimension.
UkfSettings apply_ukf_params(const UkfSettings& base, std::span<const double> physical);
// `s`' values of the tuned parameters, in ukf_space() order.
std::vector<double> ukf_params_of(const UkfSettings& s);

// The fusion of `in` with `s` (static kinematic odometry) and its position
// errors against the ground truth; *healthy (if not null) tells whether the
// filter stayed healthy (the metrics are NaN otherwise). Throws
// std::invalid_argument for invalid settings.
objectives::ErrorMetrics ukf_pose_errors(const FusionInput& in, const UkfSettings& s, bool* healthy = nullptr);

class UkfObjective {
 public:
  // `inputs` must outlive the objective; each needs ground truth. `mode` in
  // 1..7. `base` carries the fixed parts (UT parameters, initial state,
  // which sensors are used). Throws std::invalid_argument naming a track
  // without ground truth, or for a bad mode or base.
  UkfObjective(std::vector<const FusionInput*> inputs, objectives::FitnessMode mode, UkfSettings base = {});

  double fitness(std::span<const double> x) const;
  std::pair<std::vector<double>, std::vector<double>> bounds() const { return space_.box(); }

  const objectives::BoxSpace& space() const { return space_; }
  objectives::FitnessMode mode() const { return mode_; }
  // The settings at box point x (what fitness() replays).
  UkfSettings settings_at(std::span<const double> x) const;
  long evaluations() const { return counters_->evaluations.load(); }
  long failures() const { return counters_->failures.load(); }

 private:
  struct Counters {
    std::atomic<long> evaluations{0};
    std::atomic<long> failures{0};
  };
  std::vector<const FusionInput*> inputs_;
  objectives::FitnessMode mode_;
  UkfSettings base_;
  objectives::BoxSpace space_;
  std::shared_ptr<Counters> counters_ = std::make_shared<Counters>();
};

}  // namespace odotune::learned

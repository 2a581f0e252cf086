#include <odotune/learned/ukf_objective.h>

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/why.h>
#include <odotune/objectives/ekf_objective.h>  // kDivergencePenalty

namespace odotune::learned {

namespace {

enum UkfParam : std::size_t {
  kQv = 0,
  kQw = 1,
  kOdoVarV = 2,
  kOdoVarW = 3,
  kGyroVar = 4,
  kExtVarScale = 5,
  kUkfDim = 6
};

}  // namespace

bool UkfSettings::IsValid(std::string* why) const {
  std::string inner;
  if (!params.IsValid(&inner)) {
    return core::invalid(why, "UkfParams: " + inner);
  }
  if (!noise.IsValid(&inner)) {
    return core::invalid(why, "UkfSensorNoise: " + inner);
  }
  if (!(std::isfinite(odo_var_v) && odo_var_v > 0.0)) {
    return core::invalid(why, fmt::format("odo_var_v = {} must be a finite number > 0 [(m/s)^2]", odo_var_v));
  }
  if (!(std::isfinite(odo_var_w) && odo_var_w > 0.0)) {
    return core::invalid(why, fmt::format("odo_var_w = {} must be a finite number > 0 [(rad/s)^2]", odo_var_w));
  }
  return true;
}

objectives::BoxSpace ukf_space() {
  // Bounds: at least two decades either side of the defaults (UkfParams,
  // UkfSensorNoise, UkfSettings) and of the physical values of the
  // reference robots: a wheelchair accelerating at 0.5 m/s² over 0.1 s steps
  // needs q_v ≈ a²·Δt = 0.025; encoder quantisation of a few mm/s per step
  // gives odometry variances ~1e-5, a slipping wheel ~1e-1; MEMS gyros have
  // σ 0.001–0.05 rad/s.
  return objectives::BoxSpace({
      {"q_v_m2_s3", "(m/s)²/s", 1e-6, 10.0, true, "process-noise rate of V: P_VV grows by q·Δt"},
      {"q_w_rad2_s3", "(rad/s)²/s", 1e-6, 10.0, true, "process-noise rate of W: P_WW grows by q·Δt"},
      {"odo_var_v", "(m/s)²", 1e-8, 1.0, true, "static variance of the kinematic odometry's V"},
      {"odo_var_w", "(rad/s)²", 1e-8, 1.0, true, "static variance of the kinematic odometry's W"},
      {"gyro_var", "(rad/s)²", 1e-9, 1.0, true, "variance of the gyro's W (per fusion step)"},
      {"ext_var_scale", "-", 1e-2, 1e2, true, "multiplies the track's external-velocity variances"},
  });
}

UkfSettings apply_ukf_params(const UkfSettings& base, std::span<const double> v) {
  if (v.size() != kUkfDim)
    throw std::invalid_argument(fmt::format("UKF params: {} values, expected {}", v.size(), +kUkfDim));
  UkfSettings s = base;
  s.params.q_v_m2_s3 = v[kQv];
  s.params.q_w_rad2_s3 = v[kQw];
  s.odo_var_v = v[kOdoVarV];
  s.odo_var_w = v[kOdoVarW];
  s.noise.gyro_var = v[kGyroVar];
  s.noise.ext_var_scale = v[kExtVarScale];
  return s;
}

std::vector<double> ukf_params_of(const UkfSettings& s) {
  std::vector<double> v(kUkfDim);
  v[kQv] = s.params.q_v_m2_s3;
  v[kQw] = s.params.q_w_rad2_s3;
  v[kOdoVarV] = s.odo_var_v;
  v[kOdoVarW] = s.odo_var_w;
  v[kGyroVar] = s.noise.gyro_var;
  v[kExtVarScale] = s.noise.ext_var_scale;
  return v;
}

objectives::ErrorMetrics ukf_pose_errors(const FusionInput& in, const UkfSettings& s, bool* healthy) {
  std::string why;
  if (!s.IsValid(&why)) throw std::invalid_argument("UKF settings: " + why);
  const FusionTrace trace = replay_fusion(in, static_odometry(in, s.odo_var_v, s.odo_var_w), s.params, s.noise);
  if (healthy) *healthy = trace.healthy;
  return fusion_pose_errors(in, trace);
}

UkfObjective::UkfObjective(std::vector<const FusionInput*> inputs, objectives::FitnessMode mode,
                           UkfSettings base)
    : inputs_(std::move(inputs)), mode_(mode), base_(std::move(base)), space_(ukf_space()) {
  if (objectives::is_fix_cv(mode)) throw std::invalid_argument("UkfObjective: mode must be 1..7");
  if (inputs_.empty()) throw std::invalid_argument("UkfObjective: no track");
  std::string why;
  if (!base_.IsValid(&why)) throw std::invalid_argument("UkfObjective: " + why);
  for (const FusionInput* in : inputs_)
    if (!in->has_gt)
      throw std::invalid_argument(fmt::format(
          "track '{}': no ground truth (gt_x, gt_y, gt_theta): the UKF's fused pose is scored against it",
          in->track_name));
}

UkfSettings UkfObjective::settings_at(std::span<const double> x) const {
  const std::vector<double> physical = space_.to_physical(x);
  return apply_ukf_params(base_, physical);
}

double UkfObjective::fitness(std::span<const double> x) const {
  counters_->evaluations.fetch_add(1, std::memory_order_relaxed);
  // Box points are clamped into the box, whose physical values are all
  // finite and > 0, so the settings are valid; a non-finite coordinate
  // (which the clamp keeps) would not be: it scores the penalty like a
  // divergence rather than throwing through the optimiser.
  try {
    const UkfSettings s = settings_at(x);
    double sum = 0.0;
    for (const FusionInput* in : inputs_) {
      bool healthy = true;
      const double f = objectives::fitness_of(ukf_pose_errors(*in, s, &healthy), mode_);
      if (!healthy || !std::isfinite(f)) {
        counters_->failures.fetch_add(1, std::memory_order_relaxed);
        return objectives::kDivergencePenalty;
      }
      sum += f;
    }
    return sum / static_cast<double>(inputs_.size());
  } catch (const std::invalid_argument&) {
    counters_->failures.fetch_add(1, std::memory_order_relaxed);
    return objectives::kDivergencePenalty;
  }
}

}  // namespace odotune::learned

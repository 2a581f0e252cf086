#include <odotune/learned/learned_fusion.h>

#include <chrono>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>

namespace odotune::learned {
namespace {

bool positive_finite(double x) { return x > 0.0 && std::isfinite(x); }

double nan() { return std::nan(""); }

void check_inputs(const FusionInput& in, const LearnedOdometryModel* model,
                  const LearnedFusionOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("learned fusion: " + why);
  const bool learned = options.odometry == LearnedFusionOptions::Odometry::learned;
  if (learned && model == nullptr)
    throw std::invalid_argument("learned fusion: learned odometry needs a model");
  if (learned && !model->IsValid(&why)) throw std::invalid_argument("learned fusion: model: " + why);
  if (learned && !model_fits(*model, in, &why)) throw std::invalid_argument("learned fusion: " + why);
  if (options.detector && options.detector->drive == SlipDrive::power && !in.has_power)
    throw std::invalid_argument(fmt::format(
        "track '{}': no motor power (power_l, power_r): the slip detector needs it", in.track_name));
  if (options.detector && options.detector->drive == SlipDrive::commands && !in.has_cmd)
    throw std::invalid_argument(fmt::format(
        "track '{}': no velocity commands (v_cmd, w_cmd): the slip detector reads them", in.track_name));
  if (options.detector && options.detector->input != in.input)
    throw std::invalid_argument(fmt::format("track '{}' gives {} odometry, the slip detector reads {}",
                                            in.track_name, tracks::to_string(in.input),
                                            tracks::to_string(options.detector->input)));
}

// The filter's state and the pose at step k into the trace.
void record(const filters::VelocityUkf& ukf, const filters::PlanarPose& pose, std::size_t k, FusionTrace& f) {
  f.v[k] = ukf.state()[filters::kV];
  f.w[k] = ukf.state()[filters::kW];
  f.var_v[k] = ukf.cov()(filters::kV, filters::kV);
  f.var_w[k] = ukf.cov()(filters::kW, filters::kW);
  f.cov_vw[k] = ukf.cov()(filters::kV, filters::kW);
  f.x[k] = pose.x_m;
  f.y[k] = pose.y_m;
  f.theta[k] = pose.theta_rad;
}

// The odometry measurement of step k: the learned nets' velocities (fed the
// filter's previous ones) or the kinematic ones, with the detector's
// variances or the static ones.
OdometryMeasurement odometry_measurement(const FusionInput& in, std::size_t k, double prev_v, double prev_w,
                                         std::optional<LearnedOdometryStepper>& odo,
                                         std::optional<SlipDetectorStepper>& detector,
                                         const LearnedFusionOptions& options) {
  OdometryMeasurement m;
  if (odo) {
    const auto vw = odo->step(in, k, std::isfinite(prev_v) ? prev_v : 0.0,
                              std::isfinite(prev_w) ? prev_w : 0.0);
    m.v_m_s = vw[0];
    m.w_rad_s = vw[1];
  } else {
    m.v_m_s = in.v_kin[k];
    m.w_rad_s = in.w_kin[k];
  }
  if (detector) {
    const auto var = detector->step(in, k);
    m.var_v = var[0];
    m.var_w = var[1];
  } else {
    m.var_v = options.static_var_v;
    m.var_w = options.static_var_w;
  }
  return m;
}

// Retraining (paper §4.2): keeps step k's windows and the UKF's velocities
// when both are confident, and refits the nets once enough are kept.
void collect_and_retrain(const FusionInput& in, std::size_t k, const OdometryMeasurement& m,
                         const FusionTrace& f, const LearnedOdometryStepper& odo, const RetrainOptions& ro,
                         SequenceSet& v_samples, SequenceSet& w_samples, LearnedOdometryModel& current,
                         LearnedFusionResult& r) {
  if (f.var_v[k] < ro.max_filter_var_v && f.var_w[k] < ro.max_filter_var_w && m.var_v < ro.max_odometry_var_v &&
      m.var_w < ro.max_odometry_var_w) {
    // A correction net's target is the filter's velocity less the kinematic one.
    const bool correction = current.target == LearnedTarget::correction;
    v_samples.add(odo.v_window().data(), f.v[k] - (correction ? in.v_kin[k] : 0.0));
    w_samples.add(odo.w_window().data(), f.w[k] - (correction ? in.w_kin[k] : 0.0));
  }
  if (static_cast<int>(v_samples.size()) < ro.samples_per_retrain) return;
  RetrainEvent ev;
  ev.step = k;
  ev.t_s = in.t[k];
  const auto start = std::chrono::steady_clock::now();
  OdometryNet v_net = current.v_net, w_net = current.w_net;
  ev.v = v_net.retrain(v_samples, ro.training);
  ev.w = w_net.retrain(w_samples, ro.training);
  ev.seconds = core::seconds_since(start);
  // A refit that failed keeps the previous nets (the robot keeps running).
  if (ev.v.usable) current.v_net = v_net;
  if (ev.w.usable) current.w_net = w_net;
  r.retrains.push_back(ev);
  v_samples.x.clear();
  v_samples.y.clear();
  w_samples.x.clear();
  w_samples.y.clear();
}

}  // namespace

bool RetrainOptions::IsValid(std::string* why) const {
  if (!enabled) return true;
  if (samples_per_retrain < 20)
    return core::invalid(why, fmt::format("samples_per_retrain = {}: expected >= 20", samples_per_retrain));
  for (double x : {max_filter_var_v, max_filter_var_w, max_odometry_var_v, max_odometry_var_w})
    if (!positive_finite(x))
      return core::invalid(why, fmt::format("retraining thresholds must be finite and > 0, got {}", x));
  return training.IsValid(why);
}

bool LearnedFusionOptions::IsValid(std::string* why) const {
  if (!positive_finite(static_var_v) || !positive_finite(static_var_w))
    return core::invalid(why, fmt::format("static_var_v = {}, static_var_w = {}: expected finite values > 0",
                                          static_var_v, static_var_w));
  std::string inner;
  if (detector && !detector->IsValid(&inner)) return core::invalid(why, "slip detector: " + inner);
  if (!ukf.IsValid(&inner)) return core::invalid(why, "ukf: " + inner);
  if (!noise.IsValid(&inner)) return core::invalid(why, "noise: " + inner);
  if (retrain.enabled && odometry != Odometry::learned)
    return core::invalid(why, "retraining needs the learned odometry (odometry = learned)");
  if (!retrain.IsValid(&inner)) return core::invalid(why, "retrain: " + inner);
  return true;
}

LearnedFusionResult run_learned_fusion(const FusionInput& in, const LearnedOdometryModel* model,
                                       const LearnedFusionOptions& options) {
  check_inputs(in, model, options);
  const bool learned = options.odometry == LearnedFusionOptions::Odometry::learned;

  const std::size_t n = in.size();
  LearnedFusionResult r;
  r.odometry.v.assign(n, 0.0);
  r.odometry.w.assign(n, 0.0);
  r.odo_var_v.assign(n, nan());
  r.odo_var_w.assign(n, nan());
  FusionTrace& f = r.filter;
  for (auto* v : {&f.v, &f.w, &f.var_v, &f.var_w, &f.cov_vw, &f.x, &f.y, &f.theta}) v->assign(n, nan());

  LearnedOdometryModel current;  // the nets as retrained so far
  if (learned) current = *model;
  std::optional<LearnedOdometryStepper> odo;
  if (learned) odo.emplace(&current);
  std::optional<SlipDetectorStepper> detector;
  if (options.detector) detector.emplace(options.detector);

  filters::VelocityUkf ukf(options.ukf);
  filters::PlanarPose pose;
  if (in.has_gt && std::isfinite(in.gt_x[0]) && std::isfinite(in.gt_theta[0]))
    pose = {in.gt_x[0], in.gt_y[0], in.gt_theta[0]};
  if (n > 0) record(ukf, pose, 0, f);

  // Retraining samples (paper §4.2): windows and the UKF's velocities.
  SequenceSet v_samples, w_samples;
  if (learned) {
    v_samples.window = current.v_net.window();
    w_samples.window = current.w_net.window();
    v_samples.inputs = w_samples.inputs = OdometryNet::kInputs;
  }

  for (std::size_t k = 1; k < n; ++k) {
    const OdometryMeasurement m = odometry_measurement(in, k, f.v[k - 1], f.w[k - 1], odo, detector, options);
    r.odometry.v[k] = m.v_m_s;
    r.odometry.w[k] = m.w_rad_s;
    r.odo_var_v[k] = m.var_v;
    r.odo_var_w[k] = m.var_w;

    fuse_step(ukf, in, k, m, options.noise);
    if (!ukf.healthy()) {
      f.healthy = false;
      break;
    }
    pose = filters::integrate_pose(pose, ukf.state()[filters::kV], ukf.state()[filters::kW], in.dt_s);
    record(ukf, pose, k, f);

    if (!options.retrain.enabled || !odo->ready()) continue;
    collect_and_retrain(in, k, m, f, *odo, options.retrain, v_samples, w_samples, current, r);
  }
  if (learned) r.final_model = current;
  return r;
}

}  // namespace odotune::learned

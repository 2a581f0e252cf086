#include <odotune/calibration/calibration_run.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/calibration/batch_calibration.h>
#include <odotune/calibration/dead_reckoning.h>
#include <odotune/core/enum_names.h>
#include <odotune/core/why.h>
#include <odotune/filters/diff_drive.h>
#include <odotune/objectives/pose_series.h>

namespace odotune::calibration {

namespace {

// Half window of the ground-truth velocities the V/W errors compare with [s]
// (a central difference over ~0.1 s), and the longest ground-truth gap they
// interpolate across [s].
constexpr double kScoreHalfWindowS = 0.05;
constexpr double kScoreMaxGapS = 0.2;

// Piecewise-constant parameters over one track: `before` until times[0],
// then params[i] from times[i] (increasing) on.
struct ParamTimeline {
  filters::OdometryParams before;
  std::vector<double> times;
  std::vector<filters::OdometryParams> params;

  const filters::OdometryParams& at(double t_s) const {
    const auto it = std::upper_bound(times.begin(), times.end(), t_s);
    return it == times.begin() ? before : params[static_cast<std::size_t>(it - times.begin()) - 1];
  }
  const filters::OdometryParams& last() const { return params.empty() ? before : params.back(); }
};

bool within(double est, double truth, double tol) { return std::abs(est - truth) <= tol * truth; }

double nan() { return std::numeric_limits<double>::quiet_NaN(); }

// Convergence per piece of the truth schedule (see TrackCalibrationScore),
// judged at `times` (the velocity samples' times, or online-pose's fixes).
void score_convergence(const CalibrationInput& in, const ParamTimeline& tl,
                       const std::vector<double>& times_all, double tol, TrackCalibrationScore* out) {
  if (!in.truth || times_all.empty()) return;
  const TruthSchedule& truth = *in.truth;
  const std::vector<double> changes = truth.change_times();
  const double t_start = in.t.front();
  // Piece p spans [start_p, end_p): start_0 = −∞, start_p = changes[p−1].
  for (std::size_t p = 0; p <= changes.size(); ++p) {
    const double lo = p == 0 ? -std::numeric_limits<double>::infinity() : changes[p - 1];
    const double hi = p < changes.size() ? changes[p] : std::numeric_limits<double>::infinity();
    std::vector<double> times;
    std::vector<filters::OdometryParams> est;
    for (double ts : times_all)
      if (ts >= lo && ts < hi) {
        times.push_back(ts);
        est.push_back(tl.at(ts));
      }
    const std::optional<double> c = convergence_time(times, est, truth.at(lo), tol);
    const double ref = p == 0 ? t_start : lo;
    const std::optional<double> rel = c ? std::optional<double>(*c - ref) : std::nullopt;
    if (p == 0)
      out->convergence_time_s = rel;
    else
      out->reconvergence_s.push_back(rel);
  }
}

// Dead reckoning and velocity errors (see TrackCalibrationScore).
void score_odometry(const CalibrationInput& in, const ParamTimeline& tl, TrackCalibrationScore* out) {
  out->pose_rmse_m = out->heading_rmse_rad = out->v_rmse_m_s = out->w_rmse_rad_s = nan();
  if (!in.has_gt) return;
  const std::size_t n = in.t.size();
  double sum_pos = 0.0, sum_head = 0.0;
  long poses = 0;
  std::size_t start = n;
  dead_reckon(
      in, [&](double t_s) -> const filters::OdometryParams& { return tl.at(t_s); },
      [&](std::size_t r, const filters::Pose& pose) {
        if (start == n) start = r;  // the first visit is the start row, not scored
        if (r == start || !in.has_gt_row(r)) return;
        const double dx = pose(filters::kX) - in.gt_x[r];
        const double dy = pose(filters::kY) - in.gt_y[r];
        const double dh = core::wrap_angle(pose(filters::kTheta) - in.gt_theta[r]);
        sum_pos += dx * dx + dy * dy;
        sum_head += dh * dh;
        ++poses;
      });
  if (poses > 0) {
    out->pose_rmse_m = std::sqrt(sum_pos / static_cast<double>(poses));
    out->heading_rmse_rad = std::sqrt(sum_head / static_cast<double>(poses));
  }

  objectives::PoseSeries gt;
  for (std::size_t r = 0; r < n; ++r)
    if (in.has_gt_row(r)) gt.push_back(in.t[r], objectives::PlanarPose{in.gt_x[r], in.gt_y[r], in.gt_theta[r]});
  double sum_v = 0.0, sum_w = 0.0;
  long count = 0;
  for (std::size_t i = 0; i < in.samples.size(); ++i) {
    const auto ref = objectives::central_difference_velocity(gt, in.sample_t[i], kScoreHalfWindowS,
                                                             kScoreMaxGapS);
    if (!ref) continue;
    const filters::BodyVelocity odo = filters::body_velocity(tl.at(in.sample_t[i]), in.samples[i].omega_l_rad_s,
                                                             in.samples[i].omega_r_rad_s);
    sum_v += (odo.v_m_s - ref->v_m_s) * (odo.v_m_s - ref->v_m_s);
    sum_w += (odo.w_rad_s - ref->w_rad_s) * (odo.w_rad_s - ref->w_rad_s);
    ++count;
  }
  if (count > 0) {
    out->v_rmse_m_s = std::sqrt(sum_v / static_cast<double>(count));
    out->w_rmse_rad_s = std::sqrt(sum_w / static_cast<double>(count));
  }
}

// Convergence judged at `times` (online-pose's fixes).
TrackCalibrationScore score_track(const CalibrationInput& in, const ParamTimeline& tl, double tol,
                                  const std::vector<double>& times) {
  TrackCalibrationScore s;
  s.track = in.track_name;
  s.final_params = tl.last();
  if (in.truth) s.truth_final = in.truth->at(in.t.back());
  score_convergence(in, tl, times, tol, &s);
  score_odometry(in, tl, &s);
  return s;
}

// Convergence judged at the velocity samples.
TrackCalibrationScore score_track(const CalibrationInput& in, const ParamTimeline& tl, double tol) {
  return score_track(in, tl, tol, in.sample_t);
}

ParamTimeline constant_timeline(const filters::OdometryParams& p) {
  ParamTimeline tl;
  tl.before = p;
  return tl;
}

// One trace row per track for a fixed-parameter method.
void add_fixed_trace_row(const CalibrationInput& in, int track, const filters::CalibEstimate& proto,
                         CalibrationTrace* trace) {
  filters::CalibEstimate e = proto;
  // At the first sample; a track without samples (pose fit) at its first
  // odometry row with a rate.
  const bool sample = !in.samples.empty();
  const std::size_t row = in.t.size() > 1 ? 1 : 0;
  e.velocity = filters::body_velocity(e.params, sample ? in.samples.front().omega_l_rad_s : in.omega_l[row],
                                      sample ? in.samples.front().omega_r_rad_s : in.omega_r[row]);
  trace->t.push_back(sample ? in.sample_t.front() : in.t[row]);
  trace->track.push_back(track);
  trace->estimate.push_back(e);
}

// What run_calibration keeps of an offline fit.
struct OfflineFit {
  filters::CalibEstimate estimate;  // the parameters and their sds
  long residuals = 0;               // velocity pairs / reference positions
  bool converged = false;
  std::string description;
};

// The fields both fits' summaries have.
template <class Summary>
OfflineFit offline_fit(const Summary& f, long residuals, std::string description) {
  OfflineFit o;
  o.estimate.params = f.params;
  o.estimate.sd_radius_left_m = f.sd_radius_left_m;
  o.estimate.sd_radius_right_m = f.sd_radius_right_m;
  o.estimate.sd_wheel_base_m = f.sd_wheel_base_m;
  o.residuals = residuals;
  o.converged = f.converged;
  o.description = std::move(description);
  return o;
}

OfflineFit offline_fit(const BatchCalibrationSummary& f) {
  return offline_fit(
      f, f.residual_pairs,
      fmt::format("velocity residuals: {} (V, W) pairs of the external velocities, Huber 3 sigma",
                  f.residual_pairs));
}

OfflineFit offline_fit(const PoseCalibrationSummary& f) {
  return offline_fit(f, f.reference_points, f.residuals);
}

// Runs an online calibrator (PfCalibrator or DualKf) over every sample.
template <class Filter>
void run_online(Filter& filter, const std::vector<const CalibrationInput*>& inputs, double tol,
                CalibrationResult* res) {
  using Clock = std::chrono::steady_clock;
  Clock::duration busy{0};
  double particle_sum = 0.0;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const CalibrationInput& in = *inputs[k];
    ParamTimeline tl;
    tl.before = filter.estimate().params;
    for (std::size_t i = 0; i < in.samples.size(); ++i) {
      const Clock::time_point t0 = Clock::now();
      const filters::CalibEstimate& e = filter.step(in.samples[i]);
      busy += Clock::now() - t0;
      particle_sum += static_cast<double>(e.particles);
      tl.times.push_back(in.sample_t[i]);
      tl.params.push_back(e.params);
      res->trace.t.push_back(tl.times.back());
      res->trace.track.push_back(static_cast<int>(k));
      res->trace.estimate.push_back(e);
      ++res->iterations;
    }
    res->tracks.push_back(score_track(in, tl, tol));
  }
  res->final_params = filter.estimate().params;
  if (res->iterations > 0) {
    const double ms = std::chrono::duration<double, std::milli>(busy).count();
    res->ms_per_iteration = ms / static_cast<double>(res->iterations);
    res->mean_particles = particle_sum / static_cast<double>(res->iterations);
  }
}

// Runs the online pose-domain calibrator over every track in turn: the
// geometry carries over, the pose starts again on each track.
void run_online_pose(filters::MemoryPair<filters::PoseCalibrator, filters::DistanceMemoryParams>& pair,
                     const std::vector<const CalibrationInput*>& inputs, const OnlinePoseOptions& o, double tol,
                     CalibrationResult* res) {
  using Clock = std::chrono::steady_clock;
  Clock::duration busy{0};
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const CalibrationInput& in = *inputs[k];
    const OnlinePoseTrack track = online_pose_track(in, o);
    pair.apply([&](filters::PoseCalibrator& f) {
      if (track.start_pose)
        f.start_at(*track.start_pose, o.known_start_sd_xy_m, o.known_start_sd_theta_rad);
      else
        f.start_from_fixes();
    });
    ParamTimeline tl;
    tl.before = pair.estimate().params;
    for (std::size_t i = 0; i < track.samples.size(); ++i) {
      const Clock::time_point t0 = Clock::now();
      const filters::CalibEstimate& e = pair.step(track.samples[i]);
      busy += Clock::now() - t0;
      ++res->iterations;
      if (!track.samples[i].has_fix) continue;
      tl.times.push_back(track.t_s[i]);
      tl.params.push_back(e.params);
      res->trace.t.push_back(track.t_s[i]);
      res->trace.track.push_back(static_cast<int>(k));
      res->trace.estimate.push_back(e);
    }
    res->tracks.push_back(score_track(in, tl, tol, tl.times));
  }
  res->final_params = pair.estimate().params;
  if (res->iterations > 0)
    res->ms_per_iteration = std::chrono::duration<double, std::milli>(busy).count() /
                            static_cast<double>(res->iterations);
}

// Runs batch-pose or batch-velocity: one fit of all inputs from the first
// input's nominal values, scored per track without convergence.
void run_offline(const std::vector<const CalibrationInput*>& inputs, const CalibrationOptions& options,
                 CalibrationResult* res) {
  const auto t0 = std::chrono::steady_clock::now();
  const OfflineFit fit = options.method == CalibrationMethod::batch_pose
                             ? offline_fit(pose_calibrate(inputs, inputs.front()->nominal, options.pose))
                             : offline_fit(batch_calibrate(inputs, inputs.front()->nominal));
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  res->iterations = fit.residuals;
  res->ms_per_iteration = fit.residuals > 0 ? ms / static_cast<double>(fit.residuals) : 0.0;
  res->batch_converged = fit.converged;
  res->batch_residuals = fit.description;
  res->final_params = fit.estimate.params;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    add_fixed_trace_row(*inputs[k], static_cast<int>(k), fit.estimate, &res->trace);
    TrackCalibrationScore score = score_track(*inputs[k], constant_timeline(fit.estimate.params),
                                              options.convergence_tolerance);
    // An offline fit of the whole track has no convergence over time.
    score.convergence_time_s.reset();
    for (auto& r : score.reconvergence_s) r.reset();
    res->tracks.push_back(std::move(score));
  }
}

}  // namespace

std::string_view to_string(CalibrationMethod m) {
  switch (m) {
    case CalibrationMethod::adaptive_pf: return "adaptive-pf";
    case CalibrationMethod::pf: return "pf";
    case CalibrationMethod::dkf: return "dkf";
    case CalibrationMethod::online_pose: return "online-pose";
    case CalibrationMethod::batch_pose: return "batch-pose";
    case CalibrationMethod::batch_velocity: return "batch-velocity";
    case CalibrationMethod::none: return "none";
  }
  return "?";
}

bool parse_calibration_method(std::string_view text, CalibrationMethod* out) {
  if (text == "batch") {
    if (out) *out = CalibrationMethod::batch_pose;
    return true;
  }
  CalibrationMethod m{};
  if (!core::parse_by_name(text, kAllCalibrationMethods, &m)) return false;
  if (out) *out = m;
  return true;
}

filters::PfCalibratorParams effective_pf_params(const CalibrationOptions& options) {
  filters::PfCalibratorParams p = options.pf;
  p.adaptive = options.method == CalibrationMethod::adaptive_pf;
  if (p.adaptive && p.particles == filters::PfCalibratorParams{}.particles)
    p.particles = filters::PfCalibratorParams::adaptive_defaults().particles;
  return p;
}

bool CalibrationOptions::IsValid(std::string* why) const {
  if (!(convergence_tolerance > 0.0 && convergence_tolerance < 1.0))
    return core::invalid(
        why, fmt::format("convergence_tolerance = {} must be in (0, 1) (a fraction of the true value)",
                         convergence_tolerance));
  std::string inner;
  if (!memory_pair.IsValid(&inner)) return core::invalid(why, "memory_pair." + inner);
  switch (method) {
    case CalibrationMethod::adaptive_pf:
    case CalibrationMethod::pf:
      if (!effective_pf_params(*this).IsValid(&inner)) return core::invalid(why, "pf." + inner);
      break;
    case CalibrationMethod::dkf:
      if (!dkf.IsValid(&inner)) return core::invalid(why, "dkf." + inner);
      break;
    case CalibrationMethod::online_pose:
      if (!online_pose.IsValid(&inner)) return core::invalid(why, "online_pose." + inner);
      break;
    case CalibrationMethod::batch_pose:
      if (!pose.IsValid(&inner)) return core::invalid(why, "pose." + inner);
      break;
    case CalibrationMethod::batch_velocity:
    case CalibrationMethod::none: break;
  }
  return true;
}

std::optional<double> convergence_time(const std::vector<double>& times,
                                       const std::vector<filters::OdometryParams>& estimates,
                                       const filters::OdometryParams& truth, double tolerance) {
  if (times.size() != estimates.size())
    throw std::invalid_argument(fmt::format("convergence_time: {} times but {} estimates", times.size(),
                                            estimates.size()));
  std::optional<double> since;
  for (std::size_t i = estimates.size(); i-- > 0;) {
    const filters::OdometryParams& e = estimates[i];
    if (!within(e.wheel_radius_right_m, truth.wheel_radius_right_m, tolerance) ||
        !within(e.wheel_radius_left_m, truth.wheel_radius_left_m, tolerance))
      break;
    since = times[i];
  }
  return since;
}

DeadReckonedPath dead_reckoned_path(const CalibrationInput& in, const filters::OdometryParams& p) {
  std::string why;
  if (!p.IsValid(&why))
    throw std::invalid_argument(fmt::format("track '{}': parameters: {}", in.track_name, why));
  DeadReckonedPath out;
  dead_reckon(
      in, [&](double) -> const filters::OdometryParams& { return p; },
      [&](std::size_t r, const filters::Pose& pose) {
        out.t.push_back(in.t[r]);
        out.x.push_back(pose(filters::kX));
        out.y.push_back(pose(filters::kY));
        out.gt_x.push_back(in.gt_x[r]);
        out.gt_y.push_back(in.gt_y[r]);
      });
  return out;
}

TrackCalibrationScore score_fixed_params(const CalibrationInput& input, const filters::OdometryParams& params,
                                         double convergence_tolerance) {
  std::string why;
  if (!params.IsValid(&why))
    throw std::invalid_argument(fmt::format("track '{}': parameters to score: {}", input.track_name, why));
  if (input.t.empty())
    throw std::invalid_argument(fmt::format("track '{}': no odometry rows to score", input.track_name));
  return score_track(input, constant_timeline(params), convergence_tolerance);
}

CalibrationResult run_calibration(const std::vector<const CalibrationInput*>& inputs,
                                  const CalibrationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("calibration options: " + why);
  if (inputs.empty()) throw std::invalid_argument("calibration: no input track");
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    if (!inputs[k]) throw std::invalid_argument(fmt::format("calibration: input {} is null", k));
    if (inputs[k]->t.empty())
      throw std::invalid_argument(fmt::format("track '{}': no odometry rows", inputs[k]->track_name));
  }
  const double tol = options.convergence_tolerance;

  CalibrationResult res;
  res.method = options.method;
  switch (options.method) {
    case CalibrationMethod::adaptive_pf:
    case CalibrationMethod::pf: {
      const filters::PfCalibratorParams p = effective_pf_params(options);
      if (p.evolution == filters::PfEvolution::evidence) {
        filters::MemoryPair<filters::PfCalibrator> pair(filters::PfCalibrator(p), p.evidence,
                                                        options.memory_pair);
        run_online(pair, inputs, tol, &res);
        res.memory_pair = true;
        res.memory_restarts = pair.changes();
      } else {
        filters::PfCalibrator pf(p);
        run_online(pf, inputs, tol, &res);
      }
      break;
    }
    case CalibrationMethod::dkf: {
      if (options.dkf.fading_memory) {
        filters::MemoryPair<filters::DualKf> pair(filters::DualKf(options.dkf), options.dkf.evidence,
                                                  options.memory_pair);
        run_online(pair, inputs, tol, &res);
        res.memory_pair = true;
        res.memory_restarts = pair.changes();
      } else {
        filters::DualKf dkf(options.dkf);
        run_online(dkf, inputs, tol, &res);
      }
      break;
    }
    case CalibrationMethod::online_pose: {
      const filters::PoseCalibratorParams& p = options.online_pose.filter;
      res.online_pose_memory = online_pose_memory(inputs, options.online_pose);
      filters::MemoryPair<filters::PoseCalibrator, filters::DistanceMemoryParams> pair(
          filters::PoseCalibrator(p), *res.online_pose_memory, options.memory_pair);
      run_online_pose(pair, inputs, options.online_pose, tol, &res);
      res.memory_pair = true;
      res.memory_restarts = pair.changes();
      break;
    }
    case CalibrationMethod::batch_pose:
    case CalibrationMethod::batch_velocity: run_offline(inputs, options, &res); break;
    case CalibrationMethod::none: {
      for (std::size_t k = 0; k < inputs.size(); ++k) {
        filters::CalibEstimate proto;
        proto.params = inputs[k]->nominal;
        add_fixed_trace_row(*inputs[k], static_cast<int>(k), proto, &res.trace);
        res.tracks.push_back(score_track(*inputs[k], constant_timeline(inputs[k]->nominal), tol));
      }
      res.final_params = inputs.back()->nominal;
      break;
    }
  }
  return res;
}

}  // namespace odotune::calibration

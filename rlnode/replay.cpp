#include "rlnode/replay.h"

#include <algorithm>
#include <cmath>
#include <queue>

#include "rlnode/frames.h"

namespace odotune::rlnode {
namespace {

namespace rl = filters::rl;

// Inputs whose measurement depends on the filter's state when they arrive.
bool needs_callback(const Input& in) { return !in.lever.isZero(0.0) || in.gravity_from_state; }

// The node's queue: earliest stamp first; equal stamps in arrival order.
struct Queued {
  std::int64_t stamp_ns;
  std::int32_t input;
  bool operator>(const Queued& o) const {
    return stamp_ns != o.stamp_ns ? stamp_ns > o.stamp_ns : input > o.input;
  }
};
using Queue = std::priority_queue<Queued, std::vector<Queued>, std::greater<>>;

// The bookkeeping of the filter that decides the schedule: whether it is
// initialised and its last measurement time.
struct Clock {
  bool initialized = false;
  std::int64_t last_ns = 0;
  void process(std::int64_t stamp_ns) {
    if (!initialized) {
      initialized = true;
      last_ns = stamp_ns;
    } else if (stamp_ns >= last_ns) {
      last_ns = stamp_ns;
    }
  }
};

}  // namespace

ReplaySettings settings_of(const RlParams& params) {
  ReplaySettings s;
  s.process_noise = params.process_noise_covariance;
  s.initial_cov = params.initial_estimate_covariance;
  s.dynamic_process_noise = params.dynamic_process_noise_covariance;
  for (const SensorParams& sp : params.sensors) {
    s.covariance_scale.push_back(1.0);
    s.thresholds.push_back({sp.pose_rejection_threshold, sp.twist_rejection_threshold,
                            sp.accel_rejection_threshold});
  }
  return s;
}

Schedule make_schedule(const Recording& rec, std::span<const FixRole> roles, std::int64_t until_ns) {
  const RlParams& p = rec.params;
  const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / p.frequency_hz));
  const auto timeout_ns = static_cast<std::int64_t>(std::llround(p.sensor_timeout_s * 1e9));
  auto role = [&](const Input& in) {
    if (in.kind != InputKind::gps || roles.empty()) return FixRole::fuse;
    return roles[static_cast<std::size_t>(in.fix)];
  };
  Schedule s;
  Queue queue, held_out;
  Clock clock;
  bool datum_pending = rec.gps_sensor >= 0 && !rec.gps_transform.fixed;
  std::size_t next = 0;
  const std::int64_t last = std::min(rec.end_ns, until_ns);
  for (std::int64_t t = rec.start_ns; t <= last; t += period_ns) {
    for (; next < rec.inputs.size() && rec.inputs[next].receive_ns <= t; ++next) {
      const Input& in = rec.inputs[next];
      const auto i = static_cast<std::int32_t>(next);
      // navsat_transform_node takes its datum at the first fix after the
      // filter has published, and publishes nothing before it.
      if (in.kind == InputKind::gps && datum_pending) {
        if (!clock.initialized) continue;
        datum_pending = false;
        s.events.push_back({Event::datum, i, t});
      }
      if (in.stamp_ns >= until_ns) continue;
      const FixRole r = role(in);
      if (needs_callback(in) && r != FixRole::absent) s.events.push_back({Event::callback, i, t});
      if (r == FixRole::fuse) queue.push({in.stamp_ns, i});
      if (r == FixRole::score) held_out.push({in.stamp_ns, i});
    }
    if (queue.empty() && clock.initialized && t - clock.last_ns >= timeout_ns) {
      s.events.push_back({Event::timeout_predict, -1, t});
      clock.last_ns = t;
    }
    while (true) {
      const bool m = !queue.empty() && queue.top().stamp_ns <= t;
      const bool h = !held_out.empty() && held_out.top().stamp_ns <= t;
      if (!m && !h) break;
      if (m && (!h || queue.top().stamp_ns <= held_out.top().stamp_ns)) {
        s.events.push_back({Event::process, queue.top().input, t});
        clock.process(queue.top().stamp_ns);
        queue.pop();
      } else {
        s.events.push_back({Event::score, held_out.top().input, t});
        held_out.pop();
      }
    }
    if (p.predict_to_current_time && clock.initialized) {
      s.events.push_back({Event::timeout_predict, -1, t});
      clock.last_ns = t;
    }
    s.events.push_back({Event::tick, -1, t});
    s.end_ns = t;
  }
  return s;
}

Eigen::Vector3d fix_in_odom(const GpsFix& fix, const GpsTransform& t) {
  return rotation_rpy(0.0, 0.0, t.rotation_rad) * (fix.p - t.grid_origin) + t.odom_origin;
}

namespace {

rl::RlEkfParams filter_params(const Recording& rec, const ReplaySettings& s) {
  rl::RlEkfParams fp;
  fp.process_noise = s.process_noise;
  fp.initial_cov = s.initial_cov;
  fp.dynamic_process_noise = s.dynamic_process_noise;
  if (rec.params.initial_state) fp.initial_state = *rec.params.initial_state;
  return fp;
}

}  // namespace

Replayer::Replayer(const Recording& rec, const ReplaySettings& settings)
    : rec_(&rec), settings_(&settings), filter_(filter_params(rec, settings)) {
  out_.gps_transform = rec.gps_transform;
}

double Replayer::threshold_of(const Input& in) const {
  const auto& t = settings_->thresholds[in.sensor];
  switch (in.kind) {
    case InputKind::twist: return t[1];
    case InputKind::acceleration: return t[2];
    default: return t[0];
  }
}

Eigen::Vector3d Replayer::take_adjust(int i) {
  for (auto it = adjust_.begin(); it != adjust_.end(); ++it) {
    if (it->first != i) continue;
    const Eigen::Vector3d a = it->second;
    adjust_.erase(it);
    return a;
  }
  return Eigen::Vector3d::Zero();
}

// navsat_transform_node's datum (computeTransform): the filter's pose at this
// fix against the fix, less the antenna's offset turned by the IMU's heading.
void Replayer::datum(int i) {
  const Input& in = rec_->inputs[i];
  const rl::State& x = filter_.state();
  const GpsFix& f = rec_->fixes[in.fix];
  GpsTransform& g = out_.gps_transform;
  const double imu_yaw = rec_->navsat_imu_yaw_rad + f.convergence_rad;
  g.grid_origin = f.p - rotation_rpy(0.0, 0.0, imu_yaw) * in.lever;
  g.odom_origin = x.segment<3>(rl::kX);
  if (rec_->params.navsat.zero_altitude) g.odom_origin.z() = 0.0;
  g.rotation_rad = x[rl::kYaw] - imu_yaw;
}

// What the callback computes from the state when the message arrives
// (prepareTwist's ω × r, prepareAcceleration's α × r − (ω × r) × ω and its
// gravity without an orientation; the GPS antenna's offset).
void Replayer::callback(int i) {
  const Input& in = rec_->inputs[i];
  const rl::State& x = filter_.state();
  const Eigen::Vector3d w = x.segment<3>(rl::kVroll);
  if (in.kind == InputKind::gps) {
    // navsat_transform_node removes the antenna's offset turned by the
    // filter's attitude from each fix.
    adjust_.emplace_back(i, -(rotation_rpy(x[rl::kRoll], x[rl::kPitch], x[rl::kYaw]) * in.lever));
    return;
  }
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  if (in.kind == InputKind::twist) {
    a = in.lever.cross(w);
  } else if (in.kind == InputKind::acceleration) {
    a = in.lever.cross(angular_acc_) - in.lever.cross(w).cross(w);
    if (in.gravity_from_state) {
      const Eigen::Matrix3d att = rotation_rpy(x[rl::kRoll], x[rl::kPitch], x[rl::kYaw]);
      a -= att.transpose() * Eigen::Vector3d(0.0, 0.0, rec_->params.gravitational_acceleration);
    }
  }
  adjust_.emplace_back(i, a);
}

void Replayer::process(int i) {
  const Input& in = rec_->inputs[i];
  const double* v = rec_->pool.data() + in.slot;
  const double scale = settings_->covariance_scale[in.sensor];
  const Eigen::Vector3d adjust = needs_callback(in) ? take_adjust(i) : Eigen::Vector3d::Zero();
  m_.time_ns = in.stamp_ns;
  m_.mask.fill(false);
  for (int a = 0; a < in.n; ++a) {
    const int r = in.idx[a];
    m_.mask[r] = true;
    m_.z[r] = v[a];
    for (int b = 0; b < in.n; ++b) m_.R(r, in.idx[b]) = scale * v[in.n + a * in.n + b];
  }
  // two_d_mode's forced members (z, a_z, …) keep their zeros: the node forces
  // them after adding these terms.
  const int components = rec_->params.two_d_mode ? 2 : 3;
  const int offset = in.kind == InputKind::acceleration ? rl::kAx : rl::kVx;
  if (in.kind == InputKind::twist || in.kind == InputKind::acceleration) {
    m_.z.segment(offset, components) += adjust.head(components);
  } else if (in.kind == InputKind::gps) {
    const GpsFix& f = rec_->fixes[in.fix];
    const Eigen::Matrix3d rot = rotation_rpy(0.0, 0.0, out_.gps_transform.rotation_rad);
    const Eigen::Matrix3d cov = scale * rot * f.cov * rot.transpose();
    const Eigen::Vector3d p = fix_in_odom(f, out_.gps_transform) + adjust;
    for (int r = rl::kX; r < rl::kX + components; ++r) {
      if (!m_.mask[r]) continue;
      m_.z[r] = p[r];
      for (int c = rl::kX; c < rl::kX + components; ++c) m_.R(r, c) = cov(r, c);
    }
  }
  m_.mahalanobis_threshold = threshold_of(in);
  ++out_.processed;
  if (!filter_.process(m_)) ++out_.rejected;
}

// The filter's position at the held-out fix's stamp (predicted from its last
// measurement, the filter itself unchanged) against the fix.
void Replayer::score(int i) {
  const Input& in = rec_->inputs[i];
  const Eigen::Vector3d adjust = needs_callback(in) ? take_adjust(i) : Eigen::Vector3d::Zero();
  if (!filter_.initialized()) return;
  const GpsFix& f = rec_->fixes[in.fix];
  ScoredFix s;
  s.fix = in.fix;
  s.stamp_ns = in.stamp_ns;
  const double dt = static_cast<double>(in.stamp_ns - filter_.last_time_ns()) * 1e-9;
  const rl::State& x = filter_.state();
  const rl::State at = dt > 0.0 ? rl::State(rl::transition(x, dt).A * x) : x;
  s.predicted = at.head<3>();
  s.predicted_yaw = at[rl::kYaw];
  s.measured = fix_in_odom(f, out_.gps_transform) + adjust;
  const Eigen::Matrix2d rot = rotation_rpy(0.0, 0.0, out_.gps_transform.rotation_rad).topLeftCorner<2, 2>();
  s.fix_cov = rot * f.cov.topLeftCorner<2, 2>() * rot.transpose();
  out_.scored.push_back(s);
}

// RosFilter::differentiateMeasurements, then the published state.
void Replayer::tick(std::int64_t t_ns, bool keep) {
  if (!filter_.initialized()) return;
  const double now = static_cast<double>(t_ns) * 1e-9;
  const Eigen::Vector3d w = filter_.state().segment<3>(rl::kVroll);
  angular_acc_ = (w - last_rates_) / (now - last_diff_s_);
  last_rates_ = w;
  last_diff_s_ = now;
  if (keep) out_.trajectory.push_back({t_ns, filter_.state()});
}

ReplayOutput Replayer::finish() && {
  out_.final_state = filter_.state();
  out_.final_cov = filter_.cov();
  out_.finite = out_.final_state.allFinite() && out_.final_cov.allFinite();
  return std::move(out_);
}

void Replayer::run(std::span<const Event> events, bool keep_trajectory) {
  for (const Event& e : events) {
    switch (e.type) {
      case Event::callback: callback(e.input); break;
      case Event::datum: datum(e.input); break;
      case Event::process: process(e.input); break;
      case Event::score: score(e.input); break;
      case Event::timeout_predict: filter_.predict_to(e.time_ns); break;
      case Event::tick: tick(e.time_ns, keep_trajectory); break;
    }
  }
}

ReplayOutput replay(const Recording& rec, const Schedule& schedule, const ReplaySettings& settings,
                    bool keep_trajectory) {
  Replayer run(rec, settings);
  run.run(schedule.events, keep_trajectory);
  return std::move(run).finish();
}

}  // namespace odotune::rlnode

#include <odotune/rlnode/replay.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <queue>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include <odotune/rlnode/frames.h>

namespace odotune::rlnode {
namespace {

namespace rl = filters::rl;

// Inputs whose measurement depends on the filter's state when they arrive.
bool needs_callback(const Input& in) { return !in.lever.isZero(0.0) || in.gravity_from_state; }

// The node's queue: earliest stamp first; equal stamps in arrival order. A
// measurement put back by a revert (smooth_lagged_data) is re-filtered.
struct Queued {
  std::int64_t stamp_ns;
  std::int32_t input;
  bool again = false;
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

// RosFilter::periodicUpdate tick by tick, as events: the callbacks, the
// revert of smooth_lagged_data (revertTo, saveFilterState,
// clearExpiredHistory), the queue's measurements and the predictions.
class Scheduler {
 public:
  Scheduler(const Recording& rec, std::span<const FixRole> roles, std::int64_t until_ns)
      : rec_(rec),
        roles_(roles),
        until_ns_(until_ns),
        timeout_ns_(static_cast<std::int64_t>(std::llround(rec.params.sensor_timeout_s * 1e9))),
        datum_pending_(rec.through_navsat() && !rec.gps_transform.fixed) {
    const NavsatParams& nv = rec.params.navsat;
    navsat_.period_ns = static_cast<std::int64_t>(std::llround(1e9 / nv.frequency_hz));
    // The node sleeps `delay` (ROS 2: its whole seconds) before it starts the
    // timer, which first fires a period later.
    const double delay_s = nv.ros2 ? std::floor(nv.delay_s) : nv.delay_s;
    navsat_.next_ns = rec.through_navsat()
                          ? rec.start_ns + static_cast<std::int64_t>(std::llround(delay_s * 1e9)) +
                                navsat_.period_ns
                          : kNever;
  }

  Schedule run() {
    const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / rec_.params.frequency_hz));
    const std::int64_t last = std::min(rec_.end_ns, until_ns_);
    for (std::int64_t t = rec_.start_ns; t <= last; t += period_ns) tick(t);
    return std::move(s_);
  }

 private:
  FixRole role(const Input& in) const {
    if (in.kind != InputKind::gps || roles_.empty()) return FixRole::fuse;
    return roles_[static_cast<std::size_t>(in.fix)];
  }
  void push(Event::Type type, std::int32_t input, std::int64_t t) { s_.events.push_back({type, input, t}); }

  void tick(std::int64_t t) {
    receive(t);
    const bool smoothing = rec_.params.smooth_lagged_data;
    if (smoothing && !queue_.empty() && queue_.top().stamp_ns < clock_.last_ns)
      revert(queue_.top().stamp_ns - 1, t);
    if (queue_.empty() && clock_.initialized && t - clock_.last_ns >= timeout_ns_) {
      push(Event::timeout_predict, -1, t);
      clock_.last_ns = t;
    }
    process_due(t);
    if (rec_.params.predict_to_current_time && clock_.initialized) {
      push(Event::timeout_predict, -1, t);
      clock_.last_ns = t;
    }
    push(Event::tick, -1, t);
    if (clock_.initialized && first_publish_ns_ == kNever) first_publish_ns_ = t;
    if (smoothing) expire(clock_.last_ns - rec_.params.history_length_ns, t);
    s_.end_ns = t;
  }

  // The callbacks of the inputs received up to t, and navsat's ticks up to t
  // in time order (an input received at a tick's time first).
  void receive(std::int64_t t) {
    while (true) {
      const std::int64_t r = next_ < rec_.inputs.size() ? rec_.inputs[next_].receive_ns : kNever;
      if (std::min(r, navsat_.next_ns) > t) break;
      if (navsat_.next_ns < r) {
        navsat_tick(navsat_.next_ns, t);
        navsat_.next_ns += navsat_.period_ns;
        continue;
      }
      const auto i = static_cast<std::int32_t>(next_++);
      const Input& in = rec_.inputs[static_cast<std::size_t>(i)];
      if (in.kind == InputKind::gps && rec_.through_navsat()) {
        navsat_fix(in, i, t);
      } else {
        enqueue(in, i, t);
      }
    }
  }

  void enqueue(const Input& in, std::int32_t i, std::int64_t t) {
    if (in.stamp_ns >= until_ns_) return;
    if (in.kind == InputKind::command) {
      push(Event::command, i, t);
      return;
    }
    const FixRole r = role(in);
    if (needs_callback(in) && r != FixRole::absent) push(Event::callback, i, t);
    if (r == FixRole::fuse) queue_.push({in.stamp_ns, i});
    if (r == FixRole::score) held_out_.push({in.stamp_ns, i});
  }

  // navsat_transform_node's gpsFixCallback: a fused fix is its latest (and,
  // until it has its transform, the datum's). Held-out and absent fixes never
  // reach it; a held-out one is scored at its stamp once the transform that
  // places it is known.
  void navsat_fix(const Input& in, std::int32_t i, std::int64_t t) {
    const FixRole r = role(in);
    if (r == FixRole::fuse) navsat_.latest = i;
    if (r == FixRole::score && !datum_pending_) enqueue(in, i, t);
  }

  // Its periodicUpdate at time `at`, handled at the filter's tick t: the
  // transform computed once the filter has published and navsat has a fix
  // and a heading (computeTransform), or else the latest fix published
  // (prepareGpsOdometry) when one came since the last.
  void navsat_tick(std::int64_t at, std::int64_t t) {
    const bool odom = first_publish_ns_ != kNever;  // has_transform_odom_, odom_updated_
    if (!navsat_.good) {
      if (!datum_pending_) {
        // The manual datum (or a fitted transform): ROS 2 sets it once the
        // filter has published, ROS 1 at its first tick.
        navsat_.good = odom || !rec_.params.navsat.ros2;
      } else if (odom && navsat_.latest >= 0 && heading_after(first_publish_ns_, at)) {
        datum_pending_ = false;
        navsat_.good = true;
        push(Event::datum, navsat_.latest, at);
      }
      return;
    }
    if (navsat_.latest < 0 || !odom) return;
    const std::int32_t i = std::exchange(navsat_.latest, -1);
    enqueue(rec_.inputs[static_cast<std::size_t>(i)], i, t);
  }

  // Whether navsat has the heading its transform needs at `at`: an IMU
  // orientation received after the filter's first output (imuCallback waits
  // for odometry), or the filter's own yaw with use_odometry_yaw.
  bool heading_after(std::int64_t odom_ns, std::int64_t at) const {
    if (rec_.params.navsat.use_odometry_yaw) return true;
    const auto* h = navsat_heading_at(rec_, at);
    return h && h->first > odom_ns;
  }

  // The queue's measurements stamped up to t, and the held-out fixes among them.
  void process_due(std::int64_t t) {
    while (true) {
      const bool m = !queue_.empty() && queue_.top().stamp_ns <= t;
      const bool h = !held_out_.empty() && held_out_.top().stamp_ns <= t;
      if (!m && !h) break;
      if (!m || (h && held_out_.top().stamp_ns < queue_.top().stamp_ns)) {
        push(Event::score, held_out_.top().input, t);
        held_out_.pop();
        continue;
      }
      const Queued q = queue_.top();
      queue_.pop();
      push(q.again ? Event::reprocess : Event::process, q.input, t);
      clock_.process(q.stamp_ns);
      if (!rec_.params.smooth_lagged_data) continue;
      measurements_.emplace_back(q.input, q.stamp_ns);
      // saveFilterState, once per time stamp.
      if (queue_.empty() || queue_.top().stamp_ns != clock_.last_ns) {
        push(Event::save, -1, t);
        states_.push_back(clock_.last_ns);
      }
    }
  }

  // revertTo(time): back to the last state saved at or before `time` (the
  // oldest kept when none is), the measurements after it queued again.
  void revert(std::int64_t time, std::int64_t t) {
    std::int32_t popped = 0;
    std::int64_t oldest = 0;
    while (!states_.empty() && states_.back() > time) {
      oldest = states_.back();
      states_.pop_back();
      ++popped;
    }
    if (states_.empty() && popped == 0) return;
    const std::int64_t state_ns = states_.empty() ? oldest : states_.back();
    push(states_.empty() ? Event::revert_oldest : Event::revert, popped, t);
    clock_.last_ns = state_ns;
    while (!measurements_.empty() && measurements_.back().second > time) {
      const auto [input, stamp] = measurements_.back();
      measurements_.pop_back();
      if (state_ns <= stamp) {
        queue_.push({stamp, input, true});
      } else {
        push(Event::forget, input, t);
      }
    }
  }

  // clearExpiredHistory(cutoff).
  void expire(std::int64_t cutoff_ns, std::int64_t t) {
    while (!measurements_.empty() && measurements_.front().second < cutoff_ns) {
      push(Event::forget, measurements_.front().first, t);
      measurements_.pop_front();
    }
    while (!states_.empty() && states_.front() < cutoff_ns) {
      push(Event::forget_state, -1, t);
      states_.pop_front();
    }
  }

  const Recording& rec_;
  std::span<const FixRole> roles_;
  std::int64_t until_ns_, timeout_ns_;
  static constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();
  bool datum_pending_;
  // navsat_transform_node's timer: its next tick, the latest fix not yet
  // published (gps_updated_), whether it has its transform (transform_good_).
  struct Navsat {
    std::int64_t next_ns = kNever, period_ns = 0;
    std::int32_t latest = -1;
    bool good = false;
  } navsat_;
  std::int64_t first_publish_ns_ = kNever;  // the filter's first output (tick)
  Schedule s_;
  Queue queue_, held_out_;
  Clock clock_;
  std::size_t next_ = 0;
  // smooth_lagged_data's history: (input, stamp) of the measurements and the
  // last measurement times of the saved states, oldest first.
  std::deque<std::pair<std::int32_t, std::int64_t>> measurements_;
  std::deque<std::int64_t> states_;
};

}  // namespace

ReplaySettings settings_of(const RlParams& params) {
  ReplaySettings s;
  s.filter = params.filter;
  s.ukf = params.ukf;
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
  return Scheduler(rec, roles, until_ns).run();
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
  if (rec.params.control.enabled) fp.control = rec.params.control.filter;
  return fp;
}

rl::Command command_of(const Recording& rec, int i) {
  const Input& in = rec.inputs[i];
  rl::Command c;
  std::copy_n(rec.pool.data() + in.slot, rl::kControlSize, c.u.begin());
  c.time_ns = in.stamp_ns;
  return c;
}

}  // namespace

namespace {

using detail::NodeState;

double threshold_of(const ReplaySettings& s, const Input& in) {
  const auto& t = s.thresholds[in.sensor];
  switch (in.kind) {
    case InputKind::twist: return t[1];
    case InputKind::acceleration: return t[2];
    default: return t[0];
  }
}

// What input i's callback added to its measurement, until it is processed.
Eigen::Vector3d take_adjust(NodeState& n, int i) {
  for (auto it = n.adjust.begin(); it != n.adjust.end(); ++it) {
    if (it->first != i) continue;
    Eigen::Vector3d a = it->second;
    n.adjust.erase(it);
    return a;
  }
  return Eigen::Vector3d::Zero();
}

// navsat_transform_node's datum (computeTransform at its tick `at`): the
// filter's pose (its last output) against the fix, less the antenna's offset
// turned by the IMU's heading.
void take_datum(const Recording& rec, int i, std::int64_t at, const rl::State& x, NodeState& n) {
  const Input& in = rec.inputs[i];
  const GpsFix& f = rec.fixes[in.fix];
  GpsTransform& g = n.out.gps_transform;
  // use_odometry_yaw: the filter's own yaw is the heading (navsat's
  // odomCallback passes the filtered orientation on as its IMU's).
  const NavsatParams& nv = rec.params.navsat;
  const double heading = nv.use_odometry_yaw ? x[rl::kYaw] + nv.magnetic_declination_radians + nv.yaw_offset
                                             : navsat_heading_at(rec, at)->second;
  const double imu_yaw = heading + f.convergence_rad;
  g.grid_origin = f.p - rotation_rpy(0.0, 0.0, imu_yaw) * in.lever;
  g.odom_origin = x.segment<3>(rl::kX);
  if (rec.params.navsat.zero_altitude) g.odom_origin.z() = 0.0;
  g.rotation_rad = x[rl::kYaw] - imu_yaw;
}

// What the callback computes from the state when the message arrives
// (prepareTwist's ω × r, prepareAcceleration's α × r − (ω × r) × ω and its
// gravity without an orientation; the GPS antenna's offset).
void run_callback(const Recording& rec, int i, const rl::State& x, NodeState& n) {
  const Input& in = rec.inputs[i];
  const Eigen::Vector3d w = x.segment<3>(rl::kVroll);
  if (in.kind == InputKind::gps) {
    // navsat_transform_node removes the antenna's offset turned by the
    // filter's attitude from each fix.
    n.adjust.emplace_back(i, -(rotation_rpy(x[rl::kRoll], x[rl::kPitch], x[rl::kYaw]) * in.lever));
    return;
  }
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  if (in.kind == InputKind::twist) {
    a = in.lever.cross(w);
  } else if (in.kind == InputKind::acceleration) {
    a = in.lever.cross(n.angular_acc) - in.lever.cross(w).cross(w);
    if (in.gravity_from_state) {
      const Eigen::Matrix3d att = rotation_rpy(x[rl::kRoll], x[rl::kPitch], x[rl::kYaw]);
      a -= att.transpose() * Eigen::Vector3d(0.0, 0.0, rec.params.gravitational_acceleration);
    }
  }
  n.adjust.emplace_back(i, a);
}

// Input i's measurement as the node enqueues it, into m (whose entries
// outside the mask are left as they were).
void make_measurement(const Recording& rec, const ReplaySettings& s, int i, NodeState& n, rl::Measurement& m) {
  const Input& in = rec.inputs[i];
  const double* v = rec.pool.data() + in.slot;
  const double scale = s.covariance_scale[in.sensor];
  const Eigen::Vector3d adjust = needs_callback(in) ? take_adjust(n, i) : Eigen::Vector3d::Zero();
  m.time_ns = in.stamp_ns;
  m.mask.fill(false);
  for (int a = 0; a < in.n; ++a) {
    const int r = in.idx[a];
    m.mask[r] = true;
    m.z[r] = v[a];
    for (int b = 0; b < in.n; ++b) m.R(r, in.idx[b]) = scale * v[in.n + a * in.n + b];
  }
  // two_d_mode's forced members (z, a_z, …) keep their zeros: the node forces
  // them after adding these terms.
  const int components = rec.params.two_d_mode ? 2 : 3;
  const int offset = in.kind == InputKind::acceleration ? rl::kAx : rl::kVx;
  if (in.kind == InputKind::twist || in.kind == InputKind::acceleration) {
    for (int c = 0; c < components; ++c) m.z[offset + c] += adjust[c];
  } else if (in.kind == InputKind::gps) {
    const GpsFix& f = rec.fixes[in.fix];
    const Eigen::Matrix3d rot = rotation_rpy(0.0, 0.0, n.out.gps_transform.rotation_rad);
    const Eigen::Matrix3d cov = scale * rot * f.cov * rot.transpose();
    const Eigen::Vector3d p = fix_in_odom(f, n.out.gps_transform) + adjust;
    for (int r = rl::kX; r < rl::kX + components; ++r) {
      if (!m.mask[r]) continue;
      m.z[r] = p[r];
      for (int c = rl::kX; c < rl::kX + components; ++c) m.R(r, c) = cov(r, c);
    }
  }
  m.mahalanobis_threshold = threshold_of(s, in);
  ++n.out.processed;
}

// The state projected by the model from the last measurement time to
// `stamp_ns` (the filter's prediction without its covariance or a control term).
rl::State projected(const rl::State& x, std::int64_t last_ns, std::int64_t stamp_ns) {
  const double dt = static_cast<double>(stamp_ns - last_ns) * 1e-9;
  return dt > 0.0 ? rl::State(rl::transition(x, dt).A * x) : x;
}

// The filter's position at the held-out fix's stamp, `at` (predicted from its
// last measurement, the filter itself unchanged), against the fix.
void score_fix(const Recording& rec, int i, bool initialized, const rl::State& at, NodeState& n) {
  const Input& in = rec.inputs[i];
  const Eigen::Vector3d adjust = needs_callback(in) ? take_adjust(n, i) : Eigen::Vector3d::Zero();
  if (!initialized) return;
  const GpsFix& f = rec.fixes[in.fix];
  ScoredFix s;
  s.fix = in.fix;
  s.stamp_ns = in.stamp_ns;
  s.predicted = at.head<3>();
  s.predicted_yaw = at[rl::kYaw];
  const GpsTransform& g = n.out.gps_transform;
  s.measured = fix_in_odom(f, g) + adjust;
  const Eigen::Matrix2d rot = rotation_rpy(0.0, 0.0, g.rotation_rad).topLeftCorner<2, 2>();
  s.fix_cov = rot * f.cov.topLeftCorner<2, 2>() * rot.transpose();
  n.out.scored.push_back(s);
}

// RosFilter::differentiateMeasurements, then the published state.
void tick(std::int64_t t_ns, const rl::State& x, bool keep, NodeState& n) {
  const double now = static_cast<double>(t_ns) * 1e-9;
  const Eigen::Vector3d w = x.segment<3>(rl::kVroll);
  n.angular_acc = (w - n.last_rates) / (now - n.last_diff_s);
  n.last_rates = w;
  n.last_diff_s = now;
  if (keep) n.out.trajectory.push_back({t_ns, x});
}

// revertTo's saved state for a revert event (the history's deque updated).
NodeState::Saved revert(NodeState& n, const Event& e) {
  NodeState::Saved s;
  for (std::int32_t k = 0; k < e.input; ++k) {
    s = std::move(n.saved.back());
    n.saved.pop_back();
  }
  if (e.type == Event::revert) s = n.saved.back();
  return s;
}

ReplayOutput finish_output(NodeState&& n, const rl::State& x, const rl::Cov& P) {
  n.out.final_state = x;
  n.out.final_cov = P;
  n.out.finite = x.allFinite() && P.allFinite();
  return std::move(n.out);
}

}  // namespace

Replayer::Replayer(const Recording& rec, const ReplaySettings& settings)
    : rec_(&rec), settings_(&settings), filter_(settings.filter, filter_params(rec, settings), settings.ukf) {
  node_.out.gps_transform = rec.gps_transform;
}

rl::RlFilter Replayer::predicted(std::int64_t stamp_ns) const {
  rl::RlFilter f = filter_;
  if (stamp_ns > f.last_time_ns()) f.predict_to(stamp_ns);
  return f;
}

// The innovation of the GPS measurement in m_, against the prediction its
// correction starts from (RlEkf::process predicts over a positive Δt first).
void Replayer::record_innovation() {
  if (!filter_.initialized() || !m_.mask[rl::kX] || !m_.mask[rl::kY]) return;
  const rl::RlFilter f = predicted(m_.time_ns);
  Innovation v;
  v.stamp_ns = m_.time_ns;
  v.nu = m_.z.head<2>() - f.state().head<2>();
  v.S = f.cov().topLeftCorner<2, 2>() + m_.R.topLeftCorner<2, 2>();
  node_.out.innovations.push_back(v);
}

ReplayOutput Replayer::finish() && { return finish_output(std::move(node_), filter_.state(), filter_.cov()); }

void Replayer::run(std::span<const Event> events, bool keep_trajectory) {
  for (const Event& e : events) {
    switch (e.type) {
      case Event::callback: run_callback(*rec_, e.input, filter_.state(), node_); break;
      case Event::datum: take_datum(*rec_, e.input, e.time_ns, filter_.state(), node_); break;
      case Event::process:
        make_measurement(*rec_, *settings_, e.input, node_, m_);
        if (settings_->innovations && rec_->inputs[e.input].kind == InputKind::gps) record_innovation();
        if (!filter_.process(m_)) ++node_.out.rejected;
        if (rec_->params.smooth_lagged_data) node_.history.insert_or_assign(e.input, m_);
        break;
      case Event::score: {
        const std::size_t before = node_.out.scored.size();
        const std::int64_t stamp = rec_->inputs[e.input].stamp_ns;
        // The filter's own prediction when it is needed: with use_control (it
        // carries the commands) or for the predicted covariance.
        const bool own = filter_.initialized() && (rec_->params.control.enabled || settings_->innovations);
        const std::optional<rl::RlFilter> f = own ? std::optional(predicted(stamp)) : std::nullopt;
        const rl::State at = f && rec_->params.control.enabled
                                 ? f->state()
                                 : projected(filter_.state(), filter_.last_time_ns(), stamp);
        score_fix(*rec_, e.input, filter_.initialized(), at, node_);
        if (settings_->innovations && node_.out.scored.size() > before)
          node_.out.scored.back().predicted_cov = f->cov().topLeftCorner<2, 2>();
        break;
      }
      case Event::timeout_predict: filter_.predict_to(e.time_ns); break;
      case Event::tick:
        if (filter_.initialized()) tick(e.time_ns, filter_.state(), keep_trajectory, node_);
        break;
      case Event::command: filter_.set_command(command_of(*rec_, e.input)); break;
      case Event::reprocess:
        if (!filter_.process(node_.history.at(e.input))) ++node_.out.rejected;
        break;
      case Event::save: node_.saved.push_back({filter_.state(), filter_.cov(), filter_.last_time_ns()}); break;
      case Event::revert:
      case Event::revert_oldest: {
        const NodeState::Saved s = revert(node_, e);
        filter_.restore(s.x, s.P, s.last_ns);
        break;
      }
      case Event::forget: node_.history.erase(e.input); break;
      case Event::forget_state: node_.saved.pop_front(); break;
    }
  }
}

ReplayOutput replay(const Recording& rec, const Schedule& schedule, const ReplaySettings& settings,
                    bool keep_trajectory) {
  Replayer run(rec, settings);
  run.run(schedule.events, keep_trajectory);
  return std::move(run).finish();
}

namespace {

std::vector<rl::RlEkfParams> lane_params(const Recording& rec, std::span<const ReplaySettings> settings) {
  std::vector<rl::RlEkfParams> p;
  for (const ReplaySettings& s : settings) {
    if (!lockstep(rec, s))
      throw std::invalid_argument(
          "BatchReplayer: the lanes run ekf_node's filter only, without use_control or smooth_lagged_data");
    p.push_back(filter_params(rec, s));
  }
  return p;
}

}  // namespace

bool lockstep(const Recording& rec, const ReplaySettings& s) {
  return s.filter == rl::RlFilterType::ekf && !rec.params.control.enabled && !rec.params.smooth_lagged_data;
}

// The filters in RlEkfLanes, the node's bookkeeping per lane by the functions
// above, as Replayer does it.
BatchReplayer::BatchReplayer(const Recording& rec, std::span<const ReplaySettings> settings)
    : rec_(&rec),
      settings_(settings),
      filter_(lane_params(rec, settings)),
      nodes_(settings.size()),
      ms_(settings.size()) {
  for (NodeState& n : nodes_) n.out.gps_transform = rec.gps_transform;
}

void BatchReplayer::run(std::span<const Event> events, bool keep) {
  auto each = [&](auto f) {
    for (int l = 0; l < filter_.lanes(); ++l) f(l, filter_.state(l));
  };
  for (const Event& e : events) {
    switch (e.type) {
      case Event::callback:
        each([&](int l, const rl::State& x) { run_callback(*rec_, e.input, x, nodes_[l]); });
        break;
      case Event::datum:
        each([&](int l, const rl::State& x) { take_datum(*rec_, e.input, e.time_ns, x, nodes_[l]); });
        break;
      case Event::process: process(e.input); break;
      case Event::score:
        each([&](int l, const rl::State& x) {
          score_fix(*rec_, e.input, filter_.initialized(),
                    projected(x, filter_.last_time_ns(), rec_->inputs[e.input].stamp_ns), nodes_[l]);
        });
        break;
      case Event::timeout_predict: filter_.predict_to(e.time_ns); break;
      case Event::tick:
        if (filter_.initialized())
          each([&](int l, const rl::State& x) { tick(e.time_ns, x, keep, nodes_[l]); });
        break;
      // no commands or history: the lanes run without use_control and smooth_lagged_data
      case Event::command:
      case Event::reprocess:
      case Event::save:
      case Event::revert:
      case Event::revert_oldest:
      case Event::forget:
      case Event::forget_state: break;
    }
  }
}

void BatchReplayer::finish(std::vector<ReplayOutput>& out) && {
  for (int l = 0; l < filter_.lanes(); ++l) {
    out.push_back(finish_output(std::move(nodes_[l]), filter_.state(l), filter_.cov(l)));
  }
}

void BatchReplayer::process(int i) {
  for (int l = 0; l < filter_.lanes(); ++l) make_measurement(*rec_, settings_[l], i, nodes_[l], ms_[l]);
  const std::uint32_t accepted = filter_.process(ms_);
  for (int l = 0; l < filter_.lanes(); ++l) {
    if ((accepted >> l & 1u) == 0) ++nodes_[l].out.rejected;
  }
}

std::vector<ReplayOutput> replay_batch(const Recording& rec, const Schedule& schedule,
                                       std::span<const ReplaySettings> settings, bool keep_trajectory) {
  std::vector<ReplayOutput> out;
  out.reserve(settings.size());
  // Lock-step settings in runs of up to kLanes; the others alone.
  std::size_t k = 0;
  while (k < settings.size()) {
    if (!lockstep(rec, settings[k])) {
      out.push_back(replay(rec, schedule, settings[k], keep_trajectory));
      ++k;
      continue;
    }
    std::size_t lanes = 1;
    while (lanes < static_cast<std::size_t>(rl::kLanes) && k + lanes < settings.size() &&
           lockstep(rec, settings[k + lanes]))
      ++lanes;
    BatchReplayer run(rec, settings.subspan(k, lanes));
    run.run(schedule.events, keep_trajectory);
    std::move(run).finish(out);
    k += lanes;
  }
  return out;
}

}  // namespace odotune::rlnode

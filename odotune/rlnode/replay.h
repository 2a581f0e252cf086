// robot_localization's ekf_node replayed on a Recording: its timer at
// `frequency` on the bag's clock (receive times), the callbacks of the
// messages received since the last tick, then the queue's measurements
// stamped up to the tick in stamp order (RosFilter::periodicUpdate and
// integrateMeasurements), the sensor-timeout prediction when the queue is
// empty, and the angular acceleration differenced from tick to tick.
// navsat_transform_node runs beside it on its own timer (periodicUpdate at its
// `frequency`, after `delay`): it takes its datum at the first tick after the
// filter has published, with its latest fix and IMU heading, and from the next
// tick on publishes its latest fix, stamped with the fix's stamp, whenever a
// new one came (navsat_transform.cpp, read for behaviour).
//
// Which message is processed when does not depend on the filter's numbers, so
// it is laid out once (Schedule) and replayed for any noise setting. Held-out
// fixes (FixRole::score) are not fused: at their stamp the filter's
// prediction is compared with them.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <limits>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

#include <odotune/filters/rl_ekf.h>
#include <odotune/filters/rl_filter.h>
#include <odotune/rlnode/recording.h>

namespace odotune::rlnode {

enum class FixRole : std::uint8_t {
  fuse,    // the node fuses it
  score,   // held out: the filter's prediction at its stamp is scored against it
  absent,  // neither (e.g. after the scored span)
};

// What a tune changes; the file's own values by settings_of().
struct ReplaySettings {
  filters::rl::RlFilterType filter = filters::rl::RlFilterType::ekf;  // ekf_node or ukf_node
  filters::rl::UkfConstants ukf;                                      // ukf_node's alpha, kappa, beta
  Matrix15 process_noise = default_process_noise();
  Matrix15 initial_cov = default_initial_estimate_covariance();
  bool dynamic_process_noise = false;
  // Per sensor (RlParams::sensors' order): a factor on the messages' own
  // covariance (1: as recorded) and the Mahalanobis thresholds [σ] of its
  // pose, twist and acceleration parts.
  std::vector<double> covariance_scale;
  std::vector<std::array<double, 3>> thresholds;
  // Also record each fused GPS fix's innovation (ReplayOutput::innovations)
  // and each held-out fix's predicted covariance (ScoredFix::predicted_cov);
  // replay() and Replayer only, not the batch replays.
  bool innovations = false;
};
ReplaySettings settings_of(const RlParams& params);

struct Event {
  // command: a cmd_vel message becomes the filter's latest control (use_control).
  // smooth_lagged_data's history: save (the filter's state after a process),
  // revert (`input` saved states dropped from the newest, then the newest
  // left restored), revert_oldest (all `input` dropped, the oldest of them
  // restored), reprocess (input's measurement as first built, filtered again),
  // forget (input's measurement leaves the history), forget_state (the oldest
  // saved state does).
  enum Type : std::uint8_t {
    callback,
    datum,
    process,
    score,
    timeout_predict,
    tick,
    command,
    save,
    revert,
    revert_oldest,
    reprocess,
    forget,
    forget_state
  };
  Type type = tick;
  std::int32_t input = -1;
  // tick time (timeout_predict, tick); datum: navsat's tick, whose heading is
  // the IMU's last before it
  std::int64_t time_ns = 0;
};

struct Schedule {
  std::vector<Event> events;
  std::int64_t end_ns = 0;  // the last tick
};

// `roles`: one per Recording::fixes entry (empty: every fix fused). Inputs
// stamped at or after `until_ns` are not given to the node (the bag cut
// there), and the timer stops there too.
Schedule make_schedule(const Recording& rec, std::span<const FixRole> roles = {},
                       std::int64_t until_ns = std::numeric_limits<std::int64_t>::max());

struct ScoredFix {
  int fix = -1;
  std::int64_t stamp_ns = 0;
  // The filter's position [m] and yaw [rad] at the fix's stamp, odom frame.
  Eigen::Vector3d predicted = Eigen::Vector3d::Zero();
  double predicted_yaw = 0.0;
  Eigen::Vector3d measured = Eigen::Vector3d::Zero();  // the fix in the odom frame [m]
  Eigen::Matrix2d fix_cov = Eigen::Matrix2d::Zero();   // its x, y covariance in the odom frame [m²]
  // With ReplaySettings::innovations: the filter's predicted x, y covariance there [m²].
  Eigen::Matrix2d predicted_cov = Eigen::Matrix2d::Zero();
};

// A fused GPS fix against the filter's prediction at its stamp: the
// innovation ν = z − H·x̂ [m] and its covariance S = H·P·Hᵀ + R [m²] (x, y).
struct Innovation {
  std::int64_t stamp_ns = 0;
  Eigen::Vector2d nu = Eigen::Vector2d::Zero();
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
};

struct TrajectoryPoint {
  std::int64_t time_ns = 0;
  filters::rl::State state;
};

struct ReplayOutput {
  filters::rl::State final_state = filters::rl::State::Zero();
  filters::rl::Cov final_cov = filters::rl::Cov::Zero();
  std::vector<ScoredFix> scored;
  std::vector<Innovation> innovations;      // with ReplaySettings::innovations
  std::vector<TrajectoryPoint> trajectory;  // after every tick, when asked
  GpsTransform gps_transform;               // as used (taken at the first fix unless fixed)
  // processed: measurements built (each once); rejected: corrections the
  // Mahalanobis gate refused, re-filtered ones (smooth_lagged_data) included.
  long processed = 0, rejected = 0;
  bool finite = true;  // false when the state or covariance stopped being finite
};

ReplayOutput replay(const Recording& rec, const Schedule& schedule, const ReplaySettings& settings,
                    bool keep_trajectory = false);

// Whether replay_batch runs `s` in lock step with others (BatchReplayer): the
// EKF's settings on a recording without use_control or smooth_lagged_data.
bool lockstep(const Recording& rec, const ReplaySettings& s);

// One replay per entry of `settings` over one schedule, each output identical
// to replay(rec, schedule, settings[k], keep_trajectory), bit for bit. EKF
// settings are replayed filters::rl::kLanes at a time in lock step
// (filters::rl::RlEkfLanes), so a batch of kLanes costs about as much as two
// or three single replays; the others (lockstep() false) one after the other.
std::vector<ReplayOutput> replay_batch(const Recording& rec, const Schedule& schedule,
                                       std::span<const ReplaySettings> settings, bool keep_trajectory = false);

namespace detail {
// What the node keeps besides its filter: each input's callback adjustment
// until the input is processed, the angular rates it differentiates, the
// output so far.
struct NodeState {
  // Per input whose callback ran and that is not yet processed: what the
  // callback added (a few at a time, so a copy of the replay stays small).
  std::vector<std::pair<int, Eigen::Vector3d>> adjust;
  // smooth_lagged_data: the saved states (oldest first) and the measurements
  // in the history, by input, as first built.
  struct Saved {
    filters::rl::State x;
    filters::rl::Cov P;
    std::int64_t last_ns = 0;
  };
  std::deque<Saved> saved;
  std::unordered_map<int, filters::rl::Measurement> history;
  Eigen::Vector3d last_rates = Eigen::Vector3d::Zero(), angular_acc = Eigen::Vector3d::Zero();
  double last_diff_s = 0.0;
  ReplayOutput out;
};
}  // namespace detail

// A replay advanced a stretch of events at a time. A copy is a checkpoint:
// schedules that share their first events (the same fix roles up to some
// tick) continue from one replay of those events instead of repeating them
// (odotune/objectives/rl_objective.h replays many outage windows so). `rec` and
// `settings` must outlive it and its copies.
class Replayer {
 public:
  Replayer(const Recording& rec, const ReplaySettings& settings);

  // Processes `events` (a stretch of a schedule, in order).
  void run(std::span<const Event> events, bool keep_trajectory = false);
  // The held-out fixes scored so far.
  const std::vector<ScoredFix>& scored() const { return node_.out.scored; }
  ReplayOutput finish() &&;

 private:
  // The filter predicted to `stamp_ns` (a copy; this one unchanged).
  filters::rl::RlFilter predicted(std::int64_t stamp_ns) const;
  void record_innovation();

  const Recording* rec_;
  const ReplaySettings* settings_;
  filters::rl::RlFilter filter_;
  detail::NodeState node_;
  filters::rl::Measurement m_;  // scratch
};

// Up to filters::rl::kLanes replays advanced in lock step, a stretch of
// events at a time (replay_batch runs it over whole schedules): each lane's
// output is its own Replayer's, bit for bit. A copy is a checkpoint, as for
// Replayer. `rec` and the settings must outlive it and its copies.
class BatchReplayer {
 public:
  // Every setting must be lockstep() (std::invalid_argument otherwise).
  BatchReplayer(const Recording& rec, std::span<const ReplaySettings> settings);

  int lanes() const { return filter_.lanes(); }
  void run(std::span<const Event> events, bool keep_trajectory = false);
  // Appends each lane's output to `out`, in the settings' order.
  void finish(std::vector<ReplayOutput>& out) &&;

 private:
  void process(int i);

  const Recording* rec_;
  std::span<const ReplaySettings> settings_;
  filters::rl::RlEkfLanes filter_;
  std::vector<detail::NodeState> nodes_;
  std::vector<filters::rl::Measurement> ms_;  // scratch, one per lane
};

// A fix in the odom frame under a GPS transform.
Eigen::Vector3d fix_in_odom(const GpsFix& fix, const GpsTransform& t);

}  // namespace odotune::rlnode

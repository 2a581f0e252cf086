// smooth_lagged_data in the replay: a pose topic that arrives 0.3 s late is
// re-filtered from the state saved before it (robot_localization's revertTo),
// which gives what the same messages give when they arrive on time, bit for
// bit; without smoothing, or with a history shorter than the lag, it does not.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/rlnode/params.h>
#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>

#include "support/ros2_bag.h"
#include "support/temp_dir.h"

namespace rl = odotune::filters::rl;
using odotune::testing_support::BagMessageSpec;
using odotune::testing_support::TempDir;

namespace {

// geometry_msgs/PoseWithCovarianceStamped in the odom frame, x and y
// variances 0.01 m².
std::vector<std::uint8_t> lagged_pose(std::int64_t stamp_ns, double x, double y) {
  odotune::testing_support::Cdr c;
  c.header(stamp_ns, "odom");
  c.put(x).put(y).put(0.0).put(0.0).put(0.0).put(0.0).put(1.0);
  for (int i = 0; i < 36; ++i) c.put(i == 0 || i == 7 ? 0.01 : 0.0);
  return c.b;
}

// 10 s: wheel odometry at 20 Hz (1 m/s), a pose 0.5 m ahead of it at 2 Hz
// received `lag_ns` after its stamp.
std::filesystem::path lagged_bag(const std::filesystem::path& dir, std::int64_t lag_ns) {
  std::vector<BagMessageSpec> msgs;
  for (int k = 0; k <= 200; ++k) {
    const std::int64_t t = 1'000'000'000 + k * 50'000'000LL;
    msgs.push_back({0, static_cast<std::uint64_t>(t), odotune::testing_support::odometry(t, 1.0, 0.0)});
    if (k % 10 == 5)
      msgs.push_back({1, static_cast<std::uint64_t>(t + lag_ns), lagged_pose(t, 0.05 * k + 0.5, 0.1)});
  }
  std::stable_sort(msgs.begin(), msgs.end(), [](const BagMessageSpec& a, const BagMessageSpec& b) {
    return a.log_time_ns < b.log_time_ns;
  });
  const auto path = dir / ("lag" + std::to_string(lag_ns) + ".mcap");
  odotune::testing_support::write_ros2_mcap(
      path, {{"/odom", "nav_msgs/msg/Odometry"}, {"/pose", "geometry_msgs/msg/PoseWithCovarianceStamped"}},
      msgs);
  return path;
}

odotune::rlnode::ReplayOutput lagged_replay(const std::filesystem::path& dir, const std::filesystem::path& bag,
                                            const std::string& smoothing) {
  const auto file = dir / "p.yaml";
  std::ofstream(file)
      << "ekf:\n  ros__parameters:\n    frequency: 20.0\n    sensor_timeout: 10.0\n"
         "    two_d_mode: true\n    odom0: /odom\n"
         "    odom0_config: [false, false, false, false, false, false, true, false, false, false, "
         "false, false, false, false, false]\n    pose0: /pose\n"
         "    pose0_config: [true, true, false, false, false, false, false, false, false, false, "
         "false, false, false, false, false]\n"
      << smoothing;
  using namespace odotune::rlnode;
  const Recording rec = load_recording(bag, read_rl_params(file));
  return replay(rec, make_schedule(rec), settings_of(rec.params));
}

}  // namespace

TEST(RlLaggedReplay, SmoothingRefiltersAsIfOnTime) {
  TempDir dir("rl-lagged");
  const auto on_time = lagged_bag(dir.path(), 0);
  const auto late = lagged_bag(dir.path(), 300'000'000);
  const std::string smooth = "    smooth_lagged_data: true\n    history_length: 1.0\n";
  const auto reference = lagged_replay(dir.path(), on_time, "");
  const auto smoothed = lagged_replay(dir.path(), late, smooth);
  EXPECT_EQ(smoothed.final_state, reference.final_state);
  EXPECT_EQ(smoothed.final_cov, reference.final_cov);
  EXPECT_EQ(smoothed.processed, reference.processed);
  // On time, smoothing finds nothing to revert: the same bits again.
  EXPECT_EQ(lagged_replay(dir.path(), on_time, smooth).final_state, reference.final_state);
  // Late without smoothing: each pose corrects the state of 0.3 s later.
  const auto unsmoothed = lagged_replay(dir.path(), late, "");
  EXPECT_NE(unsmoothed.final_state, reference.final_state);
  EXPECT_GT(std::abs(unsmoothed.final_state[rl::kX] - reference.final_state[rl::kX]), 0.01);
  // A history shorter than the lag: the oldest state kept, not the one before the pose.
  const auto short_history = lagged_replay(dir.path(), late,
                                           "    smooth_lagged_data: true\n    history_length: 0.1\n");
  EXPECT_NE(short_history.final_state, reference.final_state);
}

// The batch replays run a smoothing recording one setting at a time, each
// output its own replay's.
TEST(RlLaggedReplay, BatchRunsEachAlone) {
  TempDir dir("rl-lagged-batch");
  const auto late = lagged_bag(dir.path(), 300'000'000);
  const auto file = dir.path() / "p.yaml";
  std::ofstream(file)
      << "ekf:\n  ros__parameters:\n    frequency: 20.0\n    two_d_mode: true\n"
         "    smooth_lagged_data: true\n    history_length: 1.0\n    odom0: /odom\n"
         "    odom0_config: [false, false, false, false, false, false, true, false, false, false, "
         "false, false, false, false, false]\n    pose0: /pose\n"
         "    pose0_config: [true, true, false, false, false, false, false, false, false, false, "
         "false, false, false, false, false]\n";
  using namespace odotune::rlnode;
  const Recording rec = load_recording(late, read_rl_params(file));
  const Schedule s = make_schedule(rec);
  std::vector<ReplaySettings> settings(2, settings_of(rec.params));
  settings[1].process_noise *= 4.0;
  EXPECT_FALSE(lockstep(rec, settings[0]));
  const auto batch = replay_batch(rec, s, settings);
  for (std::size_t k = 0; k < settings.size(); ++k)
    EXPECT_EQ(batch[k].final_state, replay(rec, s, settings[k]).final_state);
}

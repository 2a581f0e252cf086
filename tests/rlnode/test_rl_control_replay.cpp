// use_control in the replay: the commands read from the bag's cmd_vel (Twist
// at its receive time, TwistStamped at its stamp), --remap, the control term
// in the estimate, and the batch replays running such a recording one by one.
#include <cmath>
#include <cstdint>
#include <fstream>
#include <stdexcept>
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

std::filesystem::path control_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

// geometry_msgs/Twist (CDR).
std::vector<std::uint8_t> control_twist(double v, double w) {
  odotune::testing_support::Cdr c;
  c.put(v).put(0.0).put(0.0).put(0.0).put(0.0).put(w);
  return c.b;
}

// 10 s at 20 Hz: the odometry measures the yaw rate only (0), the commands
// say 0.5 m/s forward from 1 s on, on `command_topic`.
std::filesystem::path control_bag(const std::filesystem::path& dir, const std::string& command_topic) {
  std::vector<BagMessageSpec> msgs;
  for (int k = 0; k <= 200; ++k) {
    const std::int64_t t = 1'000'000'000 + k * 50'000'000LL;
    msgs.push_back({0, static_cast<std::uint64_t>(t), odotune::testing_support::odometry(t, 0.0, 0.0)});
    if (k >= 20) msgs.push_back({1, static_cast<std::uint64_t>(t + 1'000'000), control_twist(0.5, 0.0)});
  }
  const auto path = dir / "control.mcap";
  odotune::testing_support::write_ros2_mcap(
      path, {{"/odom", "nav_msgs/msg/Odometry"}, {command_topic, "geometry_msgs/msg/Twist"}}, msgs);
  return path;
}

odotune::rlnode::RlParams control_params(const std::filesystem::path& dir, bool use_control) {
  return odotune::rlnode::read_rl_params(control_file(
      dir / (use_control ? "on.yaml" : "off.yaml"),
      std::string(
          "ekf:\n  ros__parameters:\n    frequency: 20.0\n    two_d_mode: true\n    odom0: /odom\n"
          "    odom0_config: [false, false, false, false, false, false, false, false, false, false, false, "
          "true, false, false, false]\n    use_control: ") +
          (use_control ? "true" : "false") +
          "\n    control_timeout: 0.2\n    control_config: [true, false, false, false, false, true]\n"
          "    acceleration_limits: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n"
          "    acceleration_gains: [2.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n"));
}

}  // namespace

// Nothing measures v_x: with use_control the commands drive it to 0.5 m/s
// (gain 2/s, so within 0.01 m/s after about 2 s) and the robot moves about
// 0.5·(9 − 0.5) m; without, it stays where it is.
TEST(RlControlReplay, CommandsDriveTheUnmeasuredVelocity) {
  TempDir dir("rl-control");
  const auto bag = control_bag(dir.path(), "/cmd_vel");
  using namespace odotune::rlnode;
  const Recording on = load_recording(bag, control_params(dir.path(), true));
  const Recording off = load_recording(bag, control_params(dir.path(), false));
  const ReplayOutput a = replay(on, make_schedule(on), settings_of(on.params));
  const ReplayOutput b = replay(off, make_schedule(off), settings_of(off.params));
  EXPECT_NEAR(a.final_state[rl::kVx], 0.5, 0.01);
  EXPECT_GT(a.final_state[rl::kX], 3.8);
  EXPECT_LT(a.final_state[rl::kX], 4.5);
  EXPECT_EQ(b.final_state[rl::kVx], 0.0);
  EXPECT_EQ(b.final_state[rl::kX], 0.0);
  bool noted = false;
  for (const std::string& n : on.notes)
    noted = noted || n.find("use_control: 181 commands read") != std::string::npos;
  EXPECT_TRUE(noted);
}

// The node subscribes to cmd_vel; a bag without it is refused naming
// use_control and --remap, and --remap cmd_vel=TOPIC reads another topic.
TEST(RlControlReplay, CommandTopicIsRemapped) {
  TempDir dir("rl-control-remap");
  const auto bag = control_bag(dir.path(), "/robot/cmd_vel");
  using namespace odotune::rlnode;
  const RlParams p = control_params(dir.path(), true);
  try {
    load_recording(bag, p);
    ADD_FAILURE() << "a bag without cmd_vel must be refused";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("use_control"), std::string::npos) << what;
    EXPECT_NE(what.find("--remap cmd_vel=TOPIC"), std::string::npos) << what;
  }
  RecordingOptions o;
  o.remap["cmd_vel"] = "/robot/cmd_vel";
  const Recording rec = load_recording(bag, p, o);
  const ReplayOutput a = replay(rec, make_schedule(rec), settings_of(rec.params));
  EXPECT_NEAR(a.final_state[rl::kVx], 0.5, 0.01);
  // an input's topic is remapped alike
  RecordingOptions both = o;
  both.remap["odom"] = "/odom";
  EXPECT_NO_THROW(load_recording(bag, p, both));
  both.remap["odom"] = "/nowhere";
  EXPECT_THROW(load_recording(bag, p, both), std::invalid_argument);
}

// replay_batch runs use_control's settings one by one, each its own replay.
TEST(RlControlReplay, BatchRunsEachAlone) {
  TempDir dir("rl-control-batch");
  const auto bag = control_bag(dir.path(), "/cmd_vel");
  using namespace odotune::rlnode;
  const Recording rec = load_recording(bag, control_params(dir.path(), true));
  const Schedule s = make_schedule(rec);
  std::vector<ReplaySettings> settings(3, settings_of(rec.params));
  settings[1].process_noise *= 10.0;
  EXPECT_FALSE(lockstep(rec, settings[0]));
  const std::vector<ReplayOutput> batch = replay_batch(rec, s, settings);
  ASSERT_EQ(batch.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const ReplayOutput one = replay(rec, s, settings[k]);
    EXPECT_EQ(batch[k].final_state, one.final_state) << k;
    EXPECT_EQ(batch[k].final_cov, one.final_cov) << k;
  }
  EXPECT_THROW(BatchReplayer(rec, settings), std::invalid_argument);
}

// odomN_pose_use_child_frame: the odometry's pose is its child frame's, turned
// into base_link's (preparePose: pose · T_child←base, the covariance by
// T_child←base's rotation, Rᵀ·Σ·R).
#include <cstdint>
#include <fstream>
#include <numbers>
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

// nav_msgs/Odometry whose pose is the frame `child`'s at (x, 0), yaw 0, with
// x and y variances 0.04 and 0.01 m².
std::vector<std::uint8_t> child_odometry(std::int64_t stamp_ns, const std::string& child, double x) {
  odotune::testing_support::Cdr c;
  c.header(stamp_ns, "odom").str(child);
  c.put(x).put(0.0).put(0.0).put(0.0).put(0.0).put(0.0).put(1.0);
  for (int i = 0; i < 36; ++i) c.put(i == 0 ? 0.04 : i == 7 ? 0.01 : i % 7 == 0 ? 0.1 : 0.0);
  c.doubles(6).doubles(36);
  return c.b;
}

odotune::rlnode::Recording child_recording(const TempDir& dir, bool use_child, const std::string& child,
                                           const odotune::rlnode::Pose3& child_in_base) {
  std::vector<BagMessageSpec> msgs;
  for (int k = 0; k <= 40; ++k) {
    const std::int64_t t = 1'000'000'000 + k * 50'000'000LL;
    msgs.push_back({0, static_cast<std::uint64_t>(t), child_odometry(t, child, 2.0 + 0.05 * k)});
  }
  const auto bag = dir.path() / "child.mcap";
  odotune::testing_support::write_ros2_mcap(bag, {{"/odom", "nav_msgs/msg/Odometry"}}, msgs);
  const auto file = dir.path() / "p.yaml";
  std::ofstream(file)
      << "ekf:\n  ros__parameters:\n    two_d_mode: true\n    odom0: /odom\n"
         "    odom0_config: [true, true, false, false, false, true, false, false, false, false, "
         "false, false, false, false, false]\n    odom0_pose_use_child_frame: "
      << (use_child ? "true" : "false") << "\n";
  odotune::rlnode::RecordingOptions o;
  o.frames[child] = child_in_base;
  return odotune::rlnode::load_recording(bag, odotune::rlnode::read_rl_params(file), o);
}

}  // namespace

// The wheels' centre 0.5 m ahead of base_link: base_link is 0.5 m behind the
// reported pose (x from 2 to 4 m); without the key, the pose is taken as base_link's.
TEST(RlChildFrame, PoseIsMovedToBaseLink) {
  TempDir dir("rl-child");
  odotune::rlnode::Pose3 ahead;
  ahead.t = {0.5, 0.0, 0.0};
  using namespace odotune::rlnode;
  const Recording with = child_recording(dir, true, "wheels", ahead);
  const Recording without = child_recording(dir, false, "wheels", ahead);
  const ReplayOutput a = replay(with, make_schedule(with), settings_of(with.params));
  const ReplayOutput b = replay(without, make_schedule(without), settings_of(without.params));
  // The filter is affine in the measured positions: shifted by −0.5 m, its
  // estimate is shifted by −0.5 m too.
  EXPECT_GT(b.final_state[rl::kX], 3.0);
  EXPECT_NEAR(a.final_state[rl::kX], b.final_state[rl::kX] - 0.5, 1e-9);
  EXPECT_NEAR(a.final_state[rl::kY], 0.0, 1e-9);
}

// A child frame turned 90° about z: base_link's yaw is −90°, and the x and y
// variances trade places (Rᵀ·diag(0.04, 0.01)·R with R = Rz(−90°)).
TEST(RlChildFrame, RotatedChildFrameTurnsPoseAndCovariance) {
  TempDir dir("rl-child-rot");
  odotune::rlnode::Pose3 turned;
  turned.R = odotune::rlnode::rotation_rpy(0.0, 0.0, std::numbers::pi / 2);
  using namespace odotune::rlnode;
  const Recording rec = child_recording(dir, true, "turned", turned);
  const Input& in = rec.inputs.front();
  ASSERT_EQ(in.kind, InputKind::pose);
  ASSERT_EQ(in.n, 10);  // x, y, yaw and two_d_mode's z, roll, pitch, v_z, v_roll, v_pitch, a_z
  // the values, then the covariance, row-major over idx
  const double* v = rec.pool.data() + in.slot;
  int x = -1, y = -1, yaw = -1;
  for (int k = 0; k < in.n; ++k) {
    if (in.idx[k] == rl::kX) x = k;
    if (in.idx[k] == rl::kY) y = k;
    if (in.idx[k] == rl::kYaw) yaw = k;
  }
  ASSERT_GE(x, 0);
  ASSERT_GE(y, 0);
  ASSERT_GE(yaw, 0);
  EXPECT_NEAR(v[yaw], -std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(v[x], 2.0, 1e-12);
  EXPECT_NEAR(v[in.n + x * in.n + x], 0.01, 1e-12);
  EXPECT_NEAR(v[in.n + y * in.n + y], 0.04, 1e-12);
  // a child frame without a transform is refused by name
  TempDir other("rl-child-missing");
  try {
    std::vector<BagMessageSpec> msgs{{0, 1'000'000'000, child_odometry(1'000'000'000, "nowhere", 0.0)}};
    const auto bag = other.path() / "b.mcap";
    odotune::testing_support::write_ros2_mcap(bag, {{"/odom", "nav_msgs/msg/Odometry"}}, msgs);
    const auto file = other.path() / "p.yaml";
    std::ofstream(file)
        << "ekf:\n  ros__parameters:\n    odom0: /odom\n    odom0_config: [true, true, false, false, "
           "false, false, false, false, false, false, false, false, false, false, false]\n"
           "    odom0_pose_use_child_frame: true\n";
    load_recording(bag, read_rl_params(file));
    ADD_FAILURE() << "a child frame without a transform must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nowhere"), std::string::npos) << e.what();
  }
}

// robot_localization's ekf_node replayed from a bag and a parameter file
// (rlnode/): its own two bag integration tests (expected final positions and
// tolerances from its test/test_ekf_localization_node_bag{1,2}.yaml, facts of
// the package), the same result from the bag's ROS 2 form, and on small bags
// made here: differential and relative inputs, a standing robot with an IMU,
// held-out fixes, refusals, the GPS heading fit.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include <GeographicLib/LocalCartesian.hpp>
#include <gtest/gtest.h>

#include <odotune/bags/bag.h>
#include <odotune/rlnode/gps_alignment.h>
#include <odotune/rlnode/params.h>
#include <odotune/rlnode/prepared_recording.h>
#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>

#include "support/rl_gps_bag.h"
#include "support/rl_test1.h"
#include "support/ros2_bag.h"
#include "support/temp_dir.h"

namespace rl = odotune::filters::rl;
using namespace odotune::rlnode;
using odotune::testing_support::BagMessageSpec;
using odotune::testing_support::BagTopicSpec;
using odotune::testing_support::TempDir;

namespace {

const std::filesystem::path kBags = std::filesystem::path(ODOTUNE_SHARED_DIR) /
                                    "data/real/robot_localization_bags";

std::filesystem::path write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

const char* kBag1Params = R"(test_ekf_localization_node_bag1_ekf:
  ros__parameters:
    frequency: 30.0
    sensor_timeout: 0.1
    two_d_mode: false
    map_frame: map
    odom_frame: odom
    base_link_frame: base_link
    world_frame: odom
    odom0: /husky_velocity_controller/odom
    imu0: /imu/data
    odom0_config: [false, false, false, false, false, false, true, true, true, false, false, false, false, false, false]
    imu0_config: [false, false, false, true, true, true, false, false, false, true, true, false, true, true, true]
    odom0_differential: false
    imu0_differential: false
    imu0_remove_gravitational_acceleration: true
    process_noise_covariance: [0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015]
)";

const char* kBag2Params = R"(test_ekf_localization_node_bag2_ekf:
  ros__parameters:
    frequency: 50.0
    sensor_timeout: 0.1
    odom0: /jackal_velocity_controller/odom
    imu0: /imu/data
    odom0_config: [false, false, false, false, false, false, true, true, true, false, false, true, false, false, false]
    imu0_config: [false, false, false, true, true, true, false, false, false, true, true, true, true, true, true]
    imu0_remove_gravitational_acceleration: true
    process_noise_covariance: [0.03, 0.03, 0.04, 0.03, 0.03, 0.06, 0.025, 0.025, 0.05, 0.002, 0.002, 0.004, 0.01, 0.01, 0.01]
)";

// robot_localization's test_ukf_localization_node_bag{1,2}.test (noetic-devel),
// in the ROS 1 form: its UKF on the same inputs, alpha 0.001, kappa 0, beta 2.
const char* kUkfBag1Params = R"(test_ukf_localization_node_bag1_ukf:
  frequency: 30
  sensor_timeout: 0.1
  two_d_mode: false
  map_frame: map
  odom_frame: odom
  base_link_frame: base_link
  world_frame: odom
  transform_time_offset: 0.0
  transform_timeout: 0.0
  odom0: /husky_velocity_controller/odom
  imu0: /imu/data
  odom0_config: [false, false, false, false, false, false, true, true, true, false, false, false, false, false, false]
  imu0_config: [false, false, false, true, true, true, false, false, false, true, true, false, true, true, true]
  odom0_differential: false
  imu0_differential: false
  odom0_relative: false
  imu0_relative: false
  imu0_remove_gravitational_acceleration: true
  print_diagnostics: true
  debug: false
  debug_out_file: debug_ukf_localization.txt
  process_noise_covariance: [0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015]
  initial_estimate_covariance: [1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9]
  alpha: 0.001
  kappa: 0
  beta: 2
)";

const char* kUkfBag2Params = R"(test_ukf_localization_node_bag2_ukf:
  frequency: 50
  sensor_timeout: 0.1
  odom0: /jackal_velocity_controller/odom
  imu0: /imu/data
  map_frame: map
  odom_frame: odom
  base_link_frame: base_link
  world_frame: odom
  odom0_config: [false, false, false, false, false, false, true, true, true, false, false, true, false, false, false]
  imu0_config: [false, false, false, true, true, true, false, false, false, true, true, true, true, true, true]
  odom0_queue_size: 10
  imu0_queue_size: 10
  imu0_remove_gravitational_acceleration: true
  process_noise_covariance: [0.03, 0.03, 0.4, 0.03, 0.03, 0.06, 0.025, 0.025, 0.05, 0.002, 0.002, 0.004, 0.01, 0.01, 0.01]
  initial_estimate_covariance: [1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9]
  alpha: 0.001
  kappa: 0
  beta: 2
)";

double distance_to(const rl::State& x, double ex, double ey, double ez) {
  return std::sqrt(std::pow(x[rl::kX] - ex, 2) + std::pow(x[rl::kY] - ey, 2) + std::pow(x[rl::kZ] - ez, 2));
}

rl::State final_state(const std::filesystem::path& bag, const RlParams& p, const RecordingOptions& o = {}) {
  const Recording rec = load_recording(bag, p, o);
  return replay(rec, make_schedule(rec), settings_of(p)).final_state;
}

}  // namespace

// robot_localization's test_ekf_localization_node_bag1: final position
// (−40.0454, −76.9988, −2.6974) m within 1.0452 m; we aim for 0.3 m.
TEST(RlReplay, Bag1EndsWhereRobotLocalizationsOwnTestExpects) {
  TempDir dir("rl-bag1");
  const RlParams p = read_rl_params(write_file(dir.path() / "bag1.yaml", kBag1Params));
  const rl::State x = final_state(kBags / "ros2/test1.mcap", p, odotune::testing_support::test1_imu_mounting());
  const double d = distance_to(x, -40.0454, -76.9988, -2.6974);
  EXPECT_LT(d, 0.3) << "final " << x.head<3>().transpose();
}

// The ROS 1 form of the same recording gives the same filter, to the tenth of
// a millimetre: the ROS 2 forms' receive times differ by up to 256 ns, which
// moves a message across a tick boundary now and then.
TEST(RlReplay, Bag1RosOneAndMcapFormsAgree) {
  if (!odotune::bags::ros1_supported()) GTEST_SKIP() << "this build does not read ROS 1 bags";
  TempDir dir("rl-bag1-forms");
  const RlParams p = read_rl_params(write_file(dir.path() / "bag1.yaml", kBag1Params));
  const rl::State a = final_state(kBags / "test1.bag", p, odotune::testing_support::test1_imu_mounting());
  const rl::State b = final_state(kBags / "ros2/test1.mcap", p, odotune::testing_support::test1_imu_mounting());
  EXPECT_LT((a - b).head<3>().norm(), 1e-3);
}

// robot_localization's test_ekf_localization_node_bag2: (1.0206, 3.4292,
// 0.7419) m within 0.1383 m.
TEST(RlReplay, Bag2EndsWhereRobotLocalizationsOwnTestExpects) {
  TempDir dir("rl-bag2");
  const RlParams p = read_rl_params(write_file(dir.path() / "bag2.yaml", kBag2Params));
  const rl::State x = final_state(kBags / "ros2/test2.mcap", p);
  EXPECT_LT(distance_to(x, 1.0206, 3.4292, 0.7419), 0.1383) << "final " << x.head<3>().transpose();
}

// robot_localization's test_ukf_localization_node_bag1: (−39.7333, −76.9820,
// −2.4427) m within 1.2910 m (ours: 0.30 m).
TEST(RlReplay, UkfBag1EndsWhereRobotLocalizationsOwnTestExpects) {
  TempDir dir("rl-ukf-bag1");
  const RlParams p = read_rl_params(write_file(dir.path() / "bag1.yaml", kUkfBag1Params));
  ASSERT_EQ(p.filter, rl::RlFilterType::ukf);
  const rl::State x = final_state(kBags / "ros2/test1.mcap", p, odotune::testing_support::test1_imu_mounting());
  const double d = distance_to(x, -39.7333, -76.9820, -2.4427);
  EXPECT_LT(d, 1.2910) << "final " << x.head<3>().transpose();
}

// robot_localization's test_ukf_localization_node_bag2: (1.0438, 3.4940,
// 0.7260) m within 0.2351 m (ours: 0.009 m).
TEST(RlReplay, UkfBag2EndsWhereRobotLocalizationsOwnTestExpects) {
  TempDir dir("rl-ukf-bag2");
  const RlParams p = read_rl_params(write_file(dir.path() / "bag2.yaml", kUkfBag2Params));
  ASSERT_EQ(p.filter, rl::RlFilterType::ukf);
  const rl::State x = final_state(kBags / "ros2/test2.mcap", p);
  const double d = distance_to(x, 1.0438, 3.4940, 0.7260);
  EXPECT_LT(d, 0.2351) << "final " << x.head<3>().transpose();
}

// reset_on_time_jump resets the node when the clock moves back; a bag played
// once never does that, so the key changes nothing in a replay.
TEST(RlReplay, ResetOnTimeJumpChangesNothingInAReplay) {
  TempDir dir("rl-time-jump");
  const RlParams a = read_rl_params(write_file(dir.path() / "a.yaml", kBag2Params));
  const RlParams b = read_rl_params(write_file(dir.path() / "b.yaml",
                                               std::string(kBag2Params) + "    reset_on_time_jump: true\n"));
  const rl::State xa = final_state(kBags / "ros2/test2.mcap", a),
                  xb = final_state(kBags / "ros2/test2.mcap", b);
  EXPECT_EQ(std::memcmp(xa.data(), xb.data(), sizeof(double) * rl::kStateSize), 0);
}

TEST(RlReplay, SameInputsGiveTheSameBits) {
  TempDir dir("rl-bits");
  const RlParams p = read_rl_params(write_file(dir.path() / "bag2.yaml", kBag2Params));
  const Recording rec = load_recording(kBags / "ros2/test2.mcap", p);
  const Schedule s = make_schedule(rec);
  const ReplayOutput a = replay(rec, s, settings_of(p)), b = replay(rec, s, settings_of(p));
  EXPECT_EQ(a.final_state, b.final_state);
  EXPECT_EQ(a.final_cov, b.final_cov);
  // Every input is processed but those that arrive or are stamped after the last tick.
  long due = 0;
  for (const Input& in : rec.inputs) due += in.stamp_ns <= s.end_ns && in.receive_ns <= s.end_ns ? 1 : 0;
  EXPECT_EQ(a.processed, due);
  EXPECT_GT(due, static_cast<long>(rec.inputs.size()) - 5);
}

namespace {

bool same_bits(const double* a, const double* b, std::size_t n) {
  return std::memcmp(a, b, n * sizeof(double)) == 0;
}

// Two replay outputs to the bit (their doubles compared as bytes, so that
// nan equals nan).
void expect_same_output(const ReplayOutput& a, const ReplayOutput& b, const std::string& what) {
  EXPECT_TRUE(same_bits(a.final_state.data(), b.final_state.data(), 15)) << what;
  EXPECT_TRUE(same_bits(a.final_cov.data(), b.final_cov.data(), 225)) << what;
  EXPECT_EQ(a.processed, b.processed) << what;
  EXPECT_EQ(a.rejected, b.rejected) << what;
  EXPECT_EQ(a.finite, b.finite) << what;
  EXPECT_TRUE(same_bits(&a.gps_transform.rotation_rad, &b.gps_transform.rotation_rad, 1)) << what;
  EXPECT_TRUE(same_bits(a.gps_transform.odom_origin.data(), b.gps_transform.odom_origin.data(), 3)) << what;
  ASSERT_EQ(a.scored.size(), b.scored.size()) << what;
  for (std::size_t k = 0; k < a.scored.size(); ++k) {
    EXPECT_EQ(a.scored[k].fix, b.scored[k].fix) << what;
    EXPECT_TRUE(same_bits(a.scored[k].predicted.data(), b.scored[k].predicted.data(), 3)) << what;
    EXPECT_TRUE(same_bits(&a.scored[k].predicted_yaw, &b.scored[k].predicted_yaw, 1)) << what;
    EXPECT_TRUE(same_bits(a.scored[k].measured.data(), b.scored[k].measured.data(), 3)) << what;
  }
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size()) << what;
  for (std::size_t k = 0; k < a.trajectory.size(); ++k) {
    EXPECT_TRUE(same_bits(a.trajectory[k].state.data(), b.trajectory[k].state.data(), 15)) << what;
  }
}

}  // namespace

// replay_batch against one replay per setting, to the bit, on the Husky
// recording with its GPS (datum, antenna-free fixes), the IMU's lever arm
// (callbacks), held-out fixes and the trajectory: 11 settings (a full batch
// and a partial one) of process noise, input covariances and thresholds that
// make some lanes reject, one with dynamic process noise, one whose
// covariance overflows.
TEST(RlReplay, BatchGivesTheBitsOfOneReplayPerSetting) {
  RecordingOptions o = odotune::testing_support::test1_imu_mounting();
  Recording rec = load_recording(kBags / "ros2/test1.mcap", read_rl_params(kBags / "husky_ekf.yaml"), o);
  rec.gps_transform = fit_gps_alignment(rec, settings_of(rec.params), 60.0).transform;
  std::vector<FixRole> roles(rec.fixes.size(), FixRole::fuse);
  for (std::size_t i = 3; i < roles.size(); i += 7) roles[i] = FixRole::score;
  const Schedule schedule = make_schedule(rec, roles);
  std::vector<ReplaySettings> settings(11, settings_of(rec.params));
  for (std::size_t k = 0; k < settings.size(); ++k) {
    ReplaySettings& s = settings[k];
    s.process_noise *= std::pow(10.0, 0.3 * (static_cast<double>(k) - 5.0));
    for (double& c : s.covariance_scale) c = std::pow(3.0, static_cast<double>(k % 3) - 1.0);
    if (k % 4 == 1) {
      for (auto& t : s.thresholds) t = {3.0, 2.0, 2.5};
    }
  }
  settings[6].dynamic_process_noise = true;
  settings[9].process_noise *= 1e306;
  settings[9].initial_cov *= 1e306;
  const std::vector<ReplayOutput> batch = replay_batch(rec, schedule, settings, true);
  ASSERT_EQ(batch.size(), settings.size());
  long rejecting = 0, finite = 0;
  for (std::size_t k = 0; k < settings.size(); ++k) {
    const ReplayOutput one = replay(rec, schedule, settings[k], true);
    expect_same_output(one, batch[k], "setting " + std::to_string(k));
    rejecting += one.rejected > 0 ? 1 : 0;
    finite += one.finite ? 1 : 0;
  }
  EXPECT_GE(rejecting, 2);
  EXPECT_EQ(finite, 10);
  EXPECT_FALSE(batch[0].scored.empty());
  // A batch of one, and of the same setting twice.
  expect_same_output(replay_batch(rec, schedule, std::span(settings).subspan(4, 1), true).front(), batch[4],
                     "alone");
  const std::vector<ReplaySettings> twice = {settings[2], settings[2]};
  expect_same_output(replay_batch(rec, schedule, twice, true).back(), batch[2], "twice");
}

namespace {

// A robot driving along x at 1 m/s for 10 s from (5, 3), its odometry's pose
// (frame odom) at 20 Hz.
std::filesystem::path driving_bag(const std::filesystem::path& dir) {
  std::vector<BagMessageSpec> msgs;
  for (int k = 0; k <= 200; ++k) {
    const std::int64_t t = 1'000'000'000 + k * 50'000'000LL;
    msgs.push_back({0, static_cast<std::uint64_t>(t),
                    odotune::testing_support::odometry(t, 1.0, 0.0, 5.0 + 0.05 * k, 3.0)});
  }
  const auto path = dir / "drive.mcap";
  odotune::testing_support::write_ros2_mcap(path, {{"/odom", "nav_msgs/msg/Odometry"}}, msgs);
  return path;
}

RlParams pose_params(const std::filesystem::path& dir, const std::string& extra) {
  return read_rl_params(write_file(dir / "p.yaml",
                                   "ekf:\n  ros__parameters:\n    frequency: 20.0\n    two_d_mode: true\n"
                                   "    odom0: /odom\n"
                                   "    odom0_config: [true, true, false, false, false, true, "
                                   "false, false, false, false, false, false, false, false, false]\n" +
                                       extra));
}

}  // namespace

// An absolute pose input puts the filter where the odometry says.
// UKF settings in a batch (between EKF ones) are replayed one by one, each
// output that of its own replay; the UKF and the EKF differ.
TEST(RlReplay, BatchWithUkfSettingsGivesEachItsOwnReplay) {
  TempDir dir("rl-ukf-batch");
  const RlParams p = read_rl_params(write_file(dir.path() / "bag2.yaml", kBag2Params));
  const Recording rec = load_recording(kBags / "ros2/test2.mcap", p);
  const Schedule schedule = make_schedule(rec);
  std::vector<ReplaySettings> settings(4, settings_of(p));
  settings[1].filter = settings[2].filter = rl::RlFilterType::ukf;
  settings[2].ukf.alpha = 0.1;
  settings[3].process_noise *= 2.0;
  const std::vector<ReplayOutput> batch = replay_batch(rec, schedule, settings);
  ASSERT_EQ(batch.size(), settings.size());
  for (std::size_t k = 0; k < settings.size(); ++k)
    expect_same_output(replay(rec, schedule, settings[k]), batch[k], "setting " + std::to_string(k));
  EXPECT_GT((batch[0].final_state - batch[1].final_state).head<3>().norm(), 1e-4);
  EXPECT_NE(batch[1].final_state, batch[2].final_state);  // alpha reaches the filter
  EXPECT_THROW(BatchReplayer(rec, std::span(settings).subspan(1, 1)), std::invalid_argument);
}

TEST(RlReplay, AbsolutePoseIsFollowed) {
  TempDir dir("rl-abs");
  const rl::State x = final_state(driving_bag(dir.path()), pose_params(dir.path(), ""));
  EXPECT_NEAR(x[rl::kX], 15.0, 1e-3);
  EXPECT_NEAR(x[rl::kY], 3.0, 1e-3);
}

// A relative input starts at zero: its first pose is subtracted.
TEST(RlReplay, RelativePoseStartsAtZero) {
  TempDir dir("rl-rel");
  const rl::State x = final_state(driving_bag(dir.path()),
                                  pose_params(dir.path(), "    odom0_relative: true\n"));
  EXPECT_NEAR(x[rl::kX], 10.0, 1e-3);
  EXPECT_NEAR(x[rl::kY], 0.0, 1e-3);
}

// A differential input becomes the velocity between consecutive poses: the
// filter moves at 1 m/s from where it starts (0), and never sees (5, 3).
TEST(RlReplay, DifferentialPoseBecomesVelocity) {
  TempDir dir("rl-diff");
  const RlParams p = pose_params(dir.path(), "    odom0_differential: true\n");
  const Recording rec = load_recording(driving_bag(dir.path()), p);
  const ReplayOutput out = replay(rec, make_schedule(rec), settings_of(p));
  EXPECT_NEAR(out.final_state[rl::kVx], 1.0, 1e-6);
  EXPECT_NEAR(out.final_state[rl::kX], 10.0, 0.1);  // the first interval is lost to the difference
  EXPECT_LT(std::abs(out.final_state[rl::kY]), 1e-6);
  EXPECT_EQ(rec.inputs.size(), 200u);  // one message fewer: the first has no predecessor
}

// A robot standing still with an IMU that feels only gravity: with gravity
// removed the accelerations are zero and the robot does not move.
TEST(RlReplay, StandingRobotWithImuStaysPut) {
  TempDir dir("rl-stand");
  std::vector<BagMessageSpec> msgs;
  for (int k = 0; k <= 300; ++k) {
    const std::int64_t t = 1'000'000'000 + k * 20'000'000LL;
    msgs.push_back({0, static_cast<std::uint64_t>(t), odotune::testing_support::odometry(t, 0.0, 0.0)});
    msgs.push_back({1, static_cast<std::uint64_t>(t),
                    odotune::testing_support::imu(t, "base_link", 0.0, 0.0, 0.0)});
  }
  const auto bag = dir.path() / "stand.mcap";
  odotune::testing_support::write_ros2_mcap(
      bag, {{"/odom", "nav_msgs/msg/Odometry"}, {"/imu", "sensor_msgs/msg/Imu"}}, msgs);
  const RlParams p = read_rl_params(write_file(
      dir.path() / "p.yaml",
      "ekf:\n  ros__parameters:\n    odom0: /odom\n"
      "    odom0_config: [false, false, false, false, false, false, true, true, false, false, false, true, "
      "false, false, false]\n    imu0: /imu\n"
      "    imu0_config: [false, false, false, true, true, true, false, false, false, true, true, true, true, true, "
      "true]\n    imu0_remove_gravitational_acceleration: true\n    gravitational_acceleration: 9.81\n"));
  const rl::State x = final_state(bag, p);
  EXPECT_LT(x.head<3>().norm(), 1e-6);
  EXPECT_LT(x.segment<3>(rl::kAx).norm(), 1e-6);
  // Without gravity removed, the IMU's 9.81 m/s² up is fused as an acceleration.
  const RlParams q = read_rl_params(write_file(
      dir.path() / "q.yaml",
      "ekf:\n  ros__parameters:\n    odom0: /odom\n"
      "    odom0_config: [false, false, false, false, false, false, true, true, false, false, false, true, "
      "false, false, false]\n    imu0: /imu\n"
      "    imu0_config: [false, false, false, true, true, true, false, false, false, true, true, true, true, true, "
      "true]\n"));
  EXPECT_GT(final_state(bag, q)[rl::kAz], 9.0);
}

TEST(RlReplay, FrameWithoutTransformIsRefusedNamingIt) {
  TempDir dir("rl-frame");
  std::vector<BagMessageSpec> msgs;
  for (int k = 0; k < 10; ++k) {
    const std::int64_t t = 1'000'000'000 + k * 20'000'000LL;
    msgs.push_back({0, static_cast<std::uint64_t>(t),
                    odotune::testing_support::imu(t, "imu_link", 0.0, 0.0, 0.1)});
  }
  const auto bag = dir.path() / "imu.mcap";
  odotune::testing_support::write_ros2_mcap(bag, {{"/imu", "sensor_msgs/msg/Imu"}}, msgs);
  const RlParams p = read_rl_params(write_file(
      dir.path() / "p.yaml", "ekf:\n  ros__parameters:\n    imu0: /imu\n    imu0_config: [false, false, "
                             "false, false, false, false, false, false, false, false, false, true, false, "
                             "false, false]\n"));
  try {
    load_recording(bag, p);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'imu_link'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--tf"), std::string::npos) << e.what();
  }
  RecordingOptions o;
  o.frames["imu_link"] = Pose3{};
  EXPECT_NEAR(final_state(bag, p, o)[rl::kVyaw], 0.1, 1e-6);
}

TEST(RlReplay, MissingTopicIsRefusedWithTheBagsTopics) {
  TempDir dir("rl-topic");
  const RlParams p = read_rl_params(write_file(dir.path() / "p.yaml", kBag2Params));
  try {
    load_recording(driving_bag(dir.path()), p);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/jackal_velocity_controller/odom"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("/odom"), std::string::npos) << e.what();
  }
}

// The rotation between the GPS's east/north and the odom frame, fitted on the
// first seconds of fixes, is the one the bag was made with; with it the fixes
// land on the odometry's path.
TEST(RlReplay, GpsHeadingFitFindsTheRotation) {
  TempDir dir("rl-gps");
  const double heading = 0.7;
  const RlParams p = read_rl_params(write_file(dir.path() / "p.yaml", odotune::testing_support::kRlGpsParams));
  Recording rec = load_recording(odotune::testing_support::rl_gps_bag(dir.path(), heading), p);
  ASSERT_EQ(rec.gps_sensor, 1);
  ASSERT_GT(rec.fixes.size(), 100u);
  const GpsAlignment a = fit_gps_alignment(rec, settings_of(p), 30.0);
  EXPECT_NEAR(a.transform.rotation_rad, -heading, 1e-3);
  EXPECT_LT(a.rms_m, 0.05);
  EXPECT_THROW(fit_gps_alignment(rec, settings_of(p), 2.0), std::invalid_argument);  // 2 s: too little driving
  rec.gps_transform = a.transform;
  // Every 3rd fix held out: the filter predicts it within centimetres.
  std::vector<FixRole> roles(rec.fixes.size(), FixRole::fuse);
  for (std::size_t i = 0; i < roles.size(); i += 3) roles[i] = FixRole::score;
  const ReplayOutput out = replay(rec, make_schedule(rec, roles), settings_of(p));
  ASSERT_EQ(out.scored.size(), (rec.fixes.size() + 2) / 3);
  double worst = 0.0;
  for (const ScoredFix& s : out.scored) worst = std::max(worst, (s.predicted - s.measured).head<2>().norm());
  EXPECT_LT(worst, 0.1);
}

// prepare_recording fits navsat's rotation with the node's default noise and
// initial covariance, not the file's (the noise a tune changes must not move
// it), and replays with it; without a fit, a bag whose fixes reach navsat
// without an IMU heading is refused, naming the flag.
TEST(RlReplay, PreparedRecordingFitsTheHeadingWithTheDefaultNoise) {
  TempDir dir("rl-prepared");
  std::string text = odotune::testing_support::kRlGpsParams;
  const std::string ones = "[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]";
  text.insert(text.find("    odom0:"),
              "    process_noise_covariance: " + ones + "\n    initial_estimate_covariance: " + ones + "\n");
  const RlParams p = read_rl_params(write_file(dir.path() / "p.yaml", text));
  const std::filesystem::path bag = odotune::testing_support::rl_gps_bag(dir.path(), 0.7);
  const PreparedRecording prepared = prepare_recording(bag, p, {}, 30.0);
  ASSERT_TRUE(prepared.alignment.has_value());
  const Recording rec = load_recording(bag, p);
  ReplaySettings defaults = settings_of(p);
  defaults.process_noise = default_process_noise();
  defaults.initial_cov = default_initial_estimate_covariance();
  const GpsAlignment want = fit_gps_alignment(rec, defaults, 30.0);
  const GpsAlignment files = fit_gps_alignment(rec, settings_of(p), 30.0);
  ASSERT_NE(files.transform.rotation_rad, want.transform.rotation_rad);  // else the test could not tell
  EXPECT_EQ(prepared.alignment->transform.rotation_rad, want.transform.rotation_rad);
  EXPECT_EQ(prepared.alignment->rms_m, want.rms_m);
  EXPECT_TRUE(prepared.rec.gps_transform.fixed);
  EXPECT_EQ(prepared.rec.gps_transform.rotation_rad, want.transform.rotation_rad);
  EXPECT_EQ(prepared.rec.gps_transform.odom_origin, want.transform.odom_origin);
  try {
    prepare_recording(bag, p, {});
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--gps-heading-fit"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
}

// The node drops a message stamped before its topic's previous one (not only
// before the first), and says how many it dropped.
TEST(RlReplay, MessageOlderThanItsPredecessorIsDropped) {
  TempDir dir("rl-order");
  const std::int64_t stamps[] = {1'000'000'000, 1'100'000'000, 1'300'000'000, 1'200'000'000, 1'400'000'000};
  std::vector<BagMessageSpec> msgs;
  std::uint64_t receive = 1'000'000'000;
  for (std::int64_t t : stamps) {
    msgs.push_back({0, receive, odotune::testing_support::odometry(t, 1.0, 0.0)});
    receive += 100'000'000;
  }
  const auto bag = dir.path() / "order.mcap";
  odotune::testing_support::write_ros2_mcap(bag, {{"/odom", "nav_msgs/msg/Odometry"}}, msgs);
  const RlParams p = read_rl_params(
      write_file(dir.path() / "p.yaml",
                 "ekf:\n  ros__parameters:\n    odom0: /odom\n    odom0_config: [false, false, false, "
                 "false, false, false, true, false, false, false, false, false, false, false, false]\n"));
  const Recording rec = load_recording(bag, p);
  ASSERT_EQ(rec.inputs.size(), 4u);
  for (const Input& in : rec.inputs) EXPECT_NE(in.stamp_ns, 1'200'000'000);
  ASSERT_EQ(rec.notes.size(), 1u);
  EXPECT_NE(rec.notes[0].find("1 message"), std::string::npos) << rec.notes[0];
}

// A twistN input (TwistWithCovarianceStamped), measured in a frame turned by
// 90° about z from base_link: its x velocity is the robot's y velocity.
TEST(RlReplay, TwistInputIsRotatedIntoBaseLink) {
  TempDir dir("rl-twist");
  std::vector<BagMessageSpec> msgs;
  for (int k = 0; k <= 100; ++k) {
    const std::int64_t t = 1'000'000'000 + k * 50'000'000LL;
    odotune::testing_support::Cdr c;
    c.header(t, "sensor");
    c.put(0.5).put(0.0).put(0.0);  // linear
    c.put(0.0).put(0.0).put(0.0);  // angular
    c.doubles(36, 0.0);
    msgs.push_back({0, static_cast<std::uint64_t>(t), c.b});
  }
  const auto bag = dir.path() / "twist.mcap";
  odotune::testing_support::write_ros2_mcap(bag, {{"/vel", "geometry_msgs/msg/TwistWithCovarianceStamped"}},
                                            msgs);
  const RlParams p = read_rl_params(
      write_file(dir.path() / "p.yaml",
                 "ekf:\n  ros__parameters:\n    two_d_mode: true\n    twist0: /vel\n    twist0_config: "
                 "[false, false, false, false, false, false, true, true, false, false, false, true, false, "
                 "false, false]\n"));
  RecordingOptions o;
  o.frames["sensor"].R = rotation_rpy(0.0, 0.0, std::numbers::pi / 2);
  const rl::State x = final_state(bag, p, o);
  EXPECT_NEAR(x[rl::kVy], 0.5, 1e-6);
  EXPECT_NEAR(x[rl::kVx], 0.0, 1e-6);
  EXPECT_NEAR(x[rl::kY], 2.5, 0.05);  // 5 s at 0.5 m/s
}

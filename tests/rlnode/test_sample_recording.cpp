// A recording made of plain samples (odotune/rlnode/sample_recording.h): which of the
// file's inputs each stream is, the refusals, and the messages as the node's
// callbacks prepare them.
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/rlnode/params.h>
#include <odotune/rlnode/replay.h>
#include <odotune/rlnode/sample_recording.h>

#include "support/temp_dir.h"

namespace {

using namespace odotune;
using testing::HasSubstr;

constexpr const char* kVelocities = "[false, false, false, false, false, false, true, true, false, "
                                    "false, false, true, false, false, false]";
constexpr const char* kPosition = "[true, true, false, false, false, false, false, false, false, "
                                  "false, false, false, false, false, false]";
constexpr const char* kYawRate = "[false, false, false, false, false, false, false, false, false, "
                                 "false, false, true, false, false, false]";
constexpr const char* kYaw = "[false, false, false, false, false, true, false, false, false, "
                             "false, false, true, false, false, false]";

struct SampleFile {
  testing_support::TempDir dir{"rl-samples"};
  rlnode::RlParams read(const std::string& inputs) {
    const auto path = dir.path() / "p.yaml";
    std::ofstream(path) << "ekf_filter_node:\n  ros__parameters:\n    frequency: 20.0\n    two_d_mode: true\n"
                        << inputs;
    return rlnode::read_rl_params(path);
  }
};

std::string input(const std::string& name, const char* config) {
  return "    " + name + ": " + name + "_topic\n    " + name + "_config: " + config + "\n";
}

std::string refusal(const rlnode::RlParams& p) {
  try {
    rlnode::sample_roles(p, "drive.csv");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// 20 s at 10 Hz: v = 0.5 m/s straight along the world's x (yaw 0), fixes at 1 Hz.
rlnode::SampleStreams straight_drive() {
  rlnode::SampleStreams st;
  st.name = "drive.csv";
  st.odometry_var_vx = 1e-3;
  st.odometry_var_vyaw = 3e-2;
  st.gyro_var = 1e-6;
  for (int k = 0; k <= 200; ++k) {
    const std::int64_t t = 1'000'000'000LL + k * 100'000'000LL;
    st.odometry.push_back({t, 0.5, 0.0});
    st.gyro.push_back({t, 0.0});
    if (k % 10 == 0) st.fixes.push_back({t, 0.05 * k, 0.0, 0.01, 0.01});
  }
  return st;
}

}  // namespace

TEST(SampleRecording, RolesFollowWhatEachInputFuses) {
  SampleFile f;
  const rlnode::RlParams p = f.read(input("odom0", kVelocities) + input("odom1", kPosition) +
                                    input("imu0", kYawRate));
  const rlnode::SampleRoles r = rlnode::sample_roles(p, "drive.csv");
  EXPECT_EQ(p.sensors[r.odometry].name, "odom0");
  EXPECT_EQ(p.sensors[r.fixes].name, "odom1");
  EXPECT_EQ(p.sensors[r.gyro].name, "imu0");
  const rlnode::RlParams pose = f.read(input("twist0", kVelocities) + input("pose0", kPosition));
  const rlnode::SampleRoles q = rlnode::sample_roles(pose, "drive.csv");
  EXPECT_EQ(pose.sensors[q.odometry].name, "twist0");
  EXPECT_EQ(pose.sensors[q.fixes].name, "pose0");
  EXPECT_EQ(q.gyro, -1);
}

TEST(SampleRecording, InputsNoStreamFitsAreRefusedByName) {
  SampleFile f;
  EXPECT_THAT(refusal(f.read(input("odom0", kVelocities) + input("imu0", kYaw))),
              AllOf(HasSubstr("drive.csv"), HasSubstr("imu0"), HasSubstr("orientation")));
  EXPECT_THAT(refusal(f.read(input("odom0", kVelocities) + input("odom1", kVelocities))),
              AllOf(HasSubstr("odom1"), HasSubstr("odom0")));
  EXPECT_THAT(refusal(f.read(input("odom0", kPosition))), HasSubstr("no odomN or twistN fuses velocities"));
  const std::string both = "[true, true, false, false, false, false, true, false, false, "
                           "false, false, false, false, false, false]";
  EXPECT_THAT(refusal(f.read(input("odom0", kVelocities) + input("odom1", both.c_str()))),
              AllOf(HasSubstr("odom1"), HasSubstr("x, y only")));
}

TEST(SampleRecording, AStreamTheFileFusesAndTheSamplesLackIsRefused) {
  SampleFile f;
  rlnode::SampleStreams st = straight_drive();
  st.gyro.clear();
  const rlnode::RlParams p = f.read(input("odom0", kVelocities) + input("odom1", kPosition) +
                                    input("imu0", kYawRate));
  try {
    rlnode::load_sample_recording(p, st, 0);
    FAIL() << "no refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("imu0"), HasSubstr("gyro_z"), HasSubstr("drive.csv")));
  }
}

TEST(SampleRecording, FixesAndOdometryReachTheFilterInTheWorldFrame) {
  SampleFile f;
  rlnode::RlParams p = f.read(input("odom0", kVelocities) + input("odom1", kPosition) +
                              input("imu0", kYawRate));
  rlnode::Vector15 x0 = rlnode::Vector15::Zero();
  p.initial_state = x0;
  const rlnode::SampleStreams st = straight_drive();
  const rlnode::Recording rec = rlnode::load_sample_recording(p, st, 0);
  EXPECT_EQ(rec.fixes.size(), st.fixes.size());
  EXPECT_EQ(rec.origin_ns, 0);
  EXPECT_EQ(rec.start_ns, st.odometry.front().stamp_ns);
  const rlnode::ReplayOutput out = rlnode::replay(rec, rlnode::make_schedule(rec), rlnode::settings_of(p));
  EXPECT_TRUE(out.finite);
  // 20 s at 0.5 m/s along x: 10 m, the fixes agreeing.
  EXPECT_NEAR(out.final_state[filters::rl::kX], 10.0, 0.05);
  EXPECT_NEAR(out.final_state[filters::rl::kY], 0.0, 0.01);
  EXPECT_NEAR(out.final_state[filters::rl::kVx], 0.5, 0.01);
  // Samples before start_ns are not given to the node.
  const rlnode::Recording later = rlnode::load_sample_recording(p, st, 11'000'000'000LL);
  EXPECT_EQ(later.start_ns, 11'000'000'000LL);
  EXPECT_EQ(later.fixes.size(), 11u);
}

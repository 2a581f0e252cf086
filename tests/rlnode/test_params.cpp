// robot_localization parameter files (odotune/rlnode/params.h): the Husky file and
// robot_localization's own ROS 2 test files read as ekf_node reads them, ROS 1
// files (sections and flat), the covariance forms, the input numbering rule,
// each refusal as one line with its line number, and the writer: in place with
// the user's comments kept, or converted to the other form, always reading back.
#include <odotune/rlnode/params.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support/temp_dir.h"

namespace {

namespace fs = std::filesystem;
using odotune::rlnode::kNoRejection;
using odotune::rlnode::Matrix15;
using odotune::rlnode::RlParams;
using odotune::rlnode::RlParamsUpdate;
using odotune::rlnode::SensorKind;
using odotune::rlnode::SensorParams;
using odotune::rlnode::UpdateMask;
using odotune::testing_support::TempDir;

const fs::path kHusky = fs::path(ODOTUNE_SHARED_DIR) / "data/real/robot_localization_bags/husky_ekf.yaml";

fs::path write_file(const TempDir& dir, const std::string& name, const std::string& text) {
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// 1-based line of the first line containing `needle`.
int line_of(const std::string& text, const std::string& needle) {
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    if (line.find(needle) != std::string::npos) return n;
  }
  return -1;
}

// The message read_rl_params throws (std::invalid_argument), or "" when it reads the file.
std::string read_error(const fs::path& file, const std::string& node_name = "") {
  try {
    odotune::rlnode::read_rl_params(file, node_name);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// A flow list of `v` in the style of robot_localization's files ("0.0", 15 a line).
std::string flow_list(const std::vector<double>& v, int indent) {
  std::string out = "[";
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i > 0) out += i % 15 == 0 ? ",\n" + std::string(static_cast<std::size_t>(indent), ' ') : ", ";
    std::string x = fmt::format("{}", v[i]);
    out += x.find_first_of(".e") == std::string::npos ? x + ".0" : x;
  }
  return out + "]";
}

std::vector<double> full_diagonal(const std::vector<double>& d) {
  std::vector<double> m(225, 0.0);
  for (std::size_t i = 0; i < 15; ++i) m[i * 15 + i] = d[i];
  return m;
}

UpdateMask mask(std::initializer_list<int> on) {
  UpdateMask m{};
  for (const int i : on) m[static_cast<std::size_t>(i)] = true;
  return m;
}

void expect_same(const RlParams& a, const RlParams& b) {
  EXPECT_EQ(a.frequency_hz, b.frequency_hz);
  EXPECT_EQ(a.sensor_timeout_s, b.sensor_timeout_s);
  EXPECT_EQ(a.two_d_mode, b.two_d_mode);
  EXPECT_EQ(a.world_frame, b.world_frame);
  EXPECT_EQ(a.base_link_frame, b.base_link_frame);
  EXPECT_TRUE(a.process_noise_covariance == b.process_noise_covariance);
  EXPECT_TRUE(a.initial_estimate_covariance == b.initial_estimate_covariance);
  EXPECT_EQ(a.initial_state.has_value(), b.initial_state.has_value());
  if (a.initial_state && b.initial_state) {
    EXPECT_TRUE(*a.initial_state == *b.initial_state);
  }
  ASSERT_EQ(a.sensors.size(), b.sensors.size());
  for (std::size_t i = 0; i < a.sensors.size(); ++i) {
    const SensorParams &s = a.sensors[i], &t = b.sensors[i];
    EXPECT_EQ(s.name, t.name);
    EXPECT_EQ(s.topic, t.topic);
    EXPECT_EQ(s.config, t.config) << s.name;
    EXPECT_EQ(s.differential, t.differential) << s.name;
    EXPECT_EQ(s.relative, t.relative) << s.name;
    EXPECT_EQ(s.pose_rejection_threshold, t.pose_rejection_threshold) << s.name;
    EXPECT_EQ(s.twist_rejection_threshold, t.twist_rejection_threshold) << s.name;
    EXPECT_EQ(s.accel_rejection_threshold, t.accel_rejection_threshold) << s.name;
    EXPECT_EQ(s.remove_gravitational_acceleration, t.remove_gravitational_acceleration) << s.name;
  }
  EXPECT_EQ(a.navsat.present, b.navsat.present);
  EXPECT_EQ(a.navsat.yaw_offset, b.navsat.yaw_offset);
  EXPECT_EQ(a.navsat.zero_altitude, b.navsat.zero_altitude);
  EXPECT_EQ(a.navsat.frequency_hz, b.navsat.frequency_hz);
}

// A ROS 1 file with comments: a section per node, integers where ROS 1 reads doubles.
const char* const kRos1File = R"(# my robot, ROS 1
ekf_se:
  frequency: 50   # Hz
  two_d_mode: true
  odom0: /wheel/odom
  odom0_config: [false, false, false, false, false, false,
                 true,  true,  false, false, false, true,
                 false, false, false]
  odom0_pose_rejection_threshold: 5   # keep me
  odom0_twist_rejection_threshold: 3.0
  imu0: /imu/data
  imu0_config: [false, false, false, true, true, true, false, false, false, true, true, true, false, false, false]
  imu0_relative: true
  imu0_linear_acceleration_rejection_threshold: 1.5
  # the diagonal
  process_noise_covariance: [0.1, 0.1, 0.1, 0.1, 0.1, 0.1,
                             0.2, 0.2, 0.2, 0.2, 0.2, 0.2,
                             0.3, 0.3, 0.3]
  odom1: /odometry/gps
  odom1_config: [true, true, false, false, false, false, false, false, false, false, false, false, false, false, false]
navsat_transform:
  magnetic_declination_radians: 0
  yaw_offset: 0
  zero_altitude: true
)";

// A tune's result: every entry distinct, off-diagonals included, values that need 17 digits.
Matrix15 tuned_matrix(double scale) {
  Matrix15 m = odotune::rlnode::default_process_noise() * scale;
  m(0, 1) = m(1, 0) = 0.1 + 0.2;
  m(5, 5) = 1.0 / 3.0;
  m(14, 14) = 3e-12;
  m(7, 7) = 42.0;
  return m;
}

RlParamsUpdate husky_update() {
  RlParamsUpdate u;
  u.process_noise_covariance = tuned_matrix(1.7);
  u.initial_estimate_covariance = odotune::rlnode::default_initial_estimate_covariance() * 4.0;
  u.rejection_thresholds = {{"odom0", {kNoRejection, 3.5, kNoRejection}}, {"imu0", {2.0, 2.5, 0.1 + 0.7}}};
  u.navsat_yaw_offset = -0.31234567890123456;
  return u;
}

void expect_updated(const RlParams& before, const RlParamsUpdate& u, const RlParams& back) {
  RlParams want = before;
  want.process_noise_covariance = *u.process_noise_covariance;
  want.initial_estimate_covariance = *u.initial_estimate_covariance;
  for (const auto& [name, thr] : u.rejection_thresholds) {
    for (SensorParams& s : want.sensors) {
      if (s.name != name) continue;
      s.pose_rejection_threshold = thr[0];
      s.twist_rejection_threshold = thr[1];
      if (s.kind == SensorKind::imu) s.accel_rejection_threshold = thr[2];
    }
  }
  if (u.navsat_yaw_offset) want.navsat.yaw_offset = *u.navsat_yaw_offset;
  expect_same(want, back);
}

}  // namespace

TEST(RlParams, ReadsHuskyFile) {
  const RlParams p = odotune::rlnode::read_rl_params(kHusky);
  EXPECT_TRUE(p.ros2);
  EXPECT_EQ(p.node_name, "ekf_filter_node");
  EXPECT_EQ(p.frequency_hz, 30.0);
  EXPECT_EQ(p.sensor_timeout_s, 0.1);
  EXPECT_FALSE(p.two_d_mode);
  EXPECT_EQ(p.world_frame, "odom");
  EXPECT_EQ(p.base_link_frame, "base_link");
  // the node's order: odomN, then poseN, twistN, imuN
  ASSERT_EQ(p.sensors.size(), 3U);
  const SensorParams &odom0 = p.sensors[0], &odom1 = p.sensors[1], &imu0 = p.sensors[2];
  EXPECT_EQ(odom0.name, "odom0");
  EXPECT_EQ(odom0.topic, "/husky_velocity_controller/odom");
  EXPECT_EQ(odom0.config, mask({6, 7, 8}));  // vx vy vz
  EXPECT_EQ(odom0.yaml_line, line_of(read_file(kHusky), "odom0: /husky_velocity_controller/odom"));
  EXPECT_EQ(odom1.name, "odom1");
  EXPECT_EQ(odom1.topic, "/odometry/gps");
  EXPECT_EQ(odom1.config, mask({0, 1}));  // x y
  EXPECT_EQ(imu0.kind, SensorKind::imu);
  EXPECT_EQ(imu0.topic, "/imu/data");
  EXPECT_EQ(imu0.config, mask({3, 4, 9, 10, 12, 13, 14}));  // roll pitch, their rates, ax ay az
  EXPECT_TRUE(imu0.remove_gravitational_acceleration);
  EXPECT_FALSE(odom0.differential || odom0.relative || imu0.differential || imu0.relative);
  for (const SensorParams& s : p.sensors) {
    EXPECT_EQ(s.pose_rejection_threshold, kNoRejection) << s.name;
    EXPECT_EQ(s.twist_rejection_threshold, kNoRejection) << s.name;
  }
  // robot_localization's defaults (FilterBase::reset)
  EXPECT_EQ(p.process_noise_covariance(0, 0), 0.05);
  EXPECT_EQ(p.process_noise_covariance(11, 11), 0.02);
  EXPECT_EQ(p.process_noise_covariance(14, 14), 0.015);
  EXPECT_EQ(p.process_noise_covariance(0, 1), 0.0);
  EXPECT_TRUE(p.process_noise_covariance == odotune::rlnode::default_process_noise());
  EXPECT_EQ(p.initial_estimate_covariance(3, 3), 1e-9);
  EXPECT_FALSE(p.initial_state.has_value());
  ASSERT_TRUE(p.navsat.present);
  EXPECT_EQ(p.navsat.node_name, "navsat_transform");
  EXPECT_TRUE(p.navsat.zero_altitude);
  EXPECT_EQ(p.navsat.frequency_hz, 30.0);
  EXPECT_EQ(p.navsat.yaw_offset, 0.0);
  EXPECT_FALSE(p.navsat.use_local_cartesian);
  EXPECT_FALSE(p.navsat.datum.has_value());
}

// robot_localization's test/test_ekf_localization_node_bag1.yaml (ROS 2), in
// short: its ekf section with the full 225-entry matrices and the test node's
// `_pose` section, which is not read.
TEST(RlParams, ReadsRos2Bag1TestFile) {
  TempDir dir;
  const std::vector<double> q = {0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025,
                                 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015};
  const std::string text = fmt::format(R"(test_ekf_localization_node_bag1_ekf:
    ros__parameters:
        use_sim_time: true
        clear_params: true
        filter_type: "ekf"
        frequency: 30.0
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
        odom0_config: [false, false, false, false, false, false, true, true, true,
                       false, false, false, false, false, false]
        imu0_config: [false, false, false, true,  true,  true, false, false, false,
                      true,  true,  false, true,  true,  true]
        odom0_differential: false
        imu0_differential: false
        odom0_relative: false
        imu0_relative: false
        imu0_remove_gravitational_acceleration: true
        print_diagnostics: true
        odom0_queue_size: 10
        imu0_queue_size: 10
        debug: false
        debug_out_file: debug_ekf_localization.txt
        process_noise_covariance: {}
        initial_estimate_covariance: {}

test_ekf_localization_node_bag1_pose:
    ros__parameters:
        clear_params: true
        final_x: -40.0454
        final_y: -76.9988
        tolerance: 1.0452
        output_location: ekf1.txt
)",
                                       flow_list(full_diagonal(q), 35),
                                       flow_list(full_diagonal(std::vector<double>(15, 1e-9)), 38));
  const RlParams p = odotune::rlnode::read_rl_params(write_file(dir, "bag1.yaml", text));
  EXPECT_TRUE(p.ros2);
  EXPECT_EQ(p.node_name, "test_ekf_localization_node_bag1_ekf");
  EXPECT_EQ(p.frequency_hz, 30.0);
  ASSERT_EQ(p.sensors.size(), 2U);
  EXPECT_EQ(p.sensors[0].name, "odom0");
  EXPECT_EQ(p.sensors[1].name, "imu0");
  EXPECT_EQ(p.sensors[1].config, mask({3, 4, 5, 9, 10, 12, 13, 14}));
  EXPECT_TRUE(p.sensors[1].remove_gravitational_acceleration);
  EXPECT_EQ(p.process_noise_covariance(2, 2), 0.06);
  EXPECT_EQ(p.process_noise_covariance(6, 6), 0.025);
  EXPECT_EQ(p.process_noise_covariance(2, 3), 0.0);
  EXPECT_EQ(p.initial_estimate_covariance(14, 14), 1e-9);
  EXPECT_FALSE(p.navsat.present);
}

// robot_localization's test/test_ekf_localization_node_bag2.yaml (ROS 2), in short.
TEST(RlParams, ReadsRos2Bag2TestFile) {
  TempDir dir;
  const std::vector<double> q = {0.03, 0.03,  0.04,  0.03,  0.03, 0.06, 0.025, 0.025,
                                 0.05, 0.002, 0.002, 0.004, 0.01, 0.01, 0.01};
  const std::string text = fmt::format(R"(test_ekf_localization_node_bag2_ekf:
    ros__parameters:
        use_sim_time: true
        clear_params: true
        filter_type: "ekf"
        frequency: 50.0
        sensor_timeout: 0.1
        odom0: /jackal_velocity_controller/odom
        imu0: /imu/data
        map_frame: map
        odom_frame: odom
        base_link_frame: base_link
        world_frame: odom
        odom0_config: [false, false, false, false, false, false, true, true, true,
                       false, false, true, false, false, false]
        odom0_relative: false
        imu0_config: [false, false, false, true, true, true, false, false, false,
                      true, true, true, true, true, true]
        odom0_queue_size: 10
        imu0_queue_size: 10
        imu0_remove_gravitational_acceleration: true
        process_noise_covariance: {}

test_ekf_localization_node_bag2_pose:
    ros__parameters:
        final_x: 1.0206
        final_y: 3.4292
        final_z: 0.7419
)",
                                       flow_list(full_diagonal(q), 35));
  const RlParams p = odotune::rlnode::read_rl_params(write_file(dir, "bag2.yaml", text));
  EXPECT_EQ(p.node_name, "test_ekf_localization_node_bag2_ekf");
  EXPECT_EQ(p.frequency_hz, 50.0);
  EXPECT_EQ(p.sensor_timeout_s, 0.1);
  ASSERT_EQ(p.sensors.size(), 2U);
  EXPECT_EQ(p.sensors[0].topic, "/jackal_velocity_controller/odom");
  EXPECT_EQ(p.sensors[0].config, mask({6, 7, 8, 11}));
  EXPECT_FALSE(p.sensors[0].differential);
  EXPECT_EQ(p.sensors[1].config, mask({3, 4, 5, 9, 10, 11, 12, 13, 14}));
  EXPECT_EQ(p.process_noise_covariance(9, 9), 0.002);
  EXPECT_EQ(p.process_noise_covariance(11, 11), 0.004);
  EXPECT_EQ(p.process_noise_covariance(14, 14), 0.01);
  // not given: the default
  EXPECT_TRUE(p.initial_estimate_covariance == odotune::rlnode::default_initial_estimate_covariance());
}

TEST(RlParams, ReadsFlatRos1FileInTheNodesOrder) {
  TempDir dir;
  const fs::path f = write_file(dir, "flat.yaml", R"(frequency: 50
odom_frame: my_odom
imu0: /imu
imu0_config: [false, false, false, true, true, true, false, false, false, false, false, false, true, true, true]
imu0_pose_rejection_threshold: 0.8
imu0_twist_rejection_threshold: 0.9
imu0_linear_acceleration_rejection_threshold: 1.1
twist0: /twist
twist0_rejection_threshold: 2.5
pose0: /pose
pose0_rejection_threshold: 3.5
pose0_differential: true
odom0: /odom
odom0_pose_rejection_threshold: 4
odom0_twist_rejection_threshold: 5.5
initial_state: [1, 2, 0, 0, 0, 0.5, 0, 0, 0, 0, 0, 0, 0, 0, 0]
)");
  const RlParams p = odotune::rlnode::read_rl_params(f);
  EXPECT_FALSE(p.ros2);
  EXPECT_EQ(p.node_name, "");
  EXPECT_EQ(p.frequency_hz, 50.0);
  EXPECT_DOUBLE_EQ(p.sensor_timeout_s, 1.0 / 50.0);  // the default: 1/frequency
  EXPECT_EQ(p.world_frame, "my_odom");               // the default: odom_frame
  ASSERT_EQ(p.sensors.size(), 4U);
  EXPECT_EQ(p.sensors[0].name, "odom0");
  EXPECT_EQ(p.sensors[1].name, "pose0");
  EXPECT_EQ(p.sensors[2].name, "twist0");
  EXPECT_EQ(p.sensors[3].name, "imu0");
  EXPECT_EQ(p.sensors[0].config, UpdateMask{});  // no _config: all false
  EXPECT_EQ(p.sensors[0].pose_rejection_threshold, 4.0);
  EXPECT_EQ(p.sensors[0].twist_rejection_threshold, 5.5);
  EXPECT_EQ(p.sensors[1].pose_rejection_threshold, 3.5);
  EXPECT_EQ(p.sensors[1].twist_rejection_threshold, kNoRejection);
  EXPECT_TRUE(p.sensors[1].differential);
  EXPECT_EQ(p.sensors[2].twist_rejection_threshold, 2.5);
  EXPECT_EQ(p.sensors[2].pose_rejection_threshold, kNoRejection);
  EXPECT_EQ(p.sensors[3].pose_rejection_threshold, 0.8);
  EXPECT_EQ(p.sensors[3].twist_rejection_threshold, 0.9);
  EXPECT_EQ(p.sensors[3].accel_rejection_threshold, 1.1);
  ASSERT_TRUE(p.initial_state.has_value());
  EXPECT_EQ((*p.initial_state)(1), 2.0);
  EXPECT_EQ((*p.initial_state)(5), 0.5);
}

TEST(RlParams, Reads15EntriesAsTheDiagonal) {
  TempDir dir;
  const RlParams p = odotune::rlnode::read_rl_params(write_file(dir, "p.yaml", kRos1File));
  EXPECT_FALSE(p.ros2);
  EXPECT_EQ(p.node_name, "ekf_se");
  EXPECT_EQ(p.process_noise_covariance(0, 0), 0.1);
  EXPECT_EQ(p.process_noise_covariance(8, 8), 0.2);
  EXPECT_EQ(p.process_noise_covariance(14, 14), 0.3);
  EXPECT_EQ(p.process_noise_covariance(0, 1), 0.0);  // not the default's: the file's diagonal alone
  EXPECT_EQ((p.process_noise_covariance.array() != 0.0).count(), 15);
}

TEST(RlParams, Reads225EntriesRowByRow) {
  TempDir dir;
  std::vector<double> m = full_diagonal(std::vector<double>(15, 1.0));
  m[1] = 0.5;     // row 0, column 1
  m[15] = 0.25;   // row 1, column 0
  m[14] = 0.125;  // row 0, column 14
  const fs::path f = write_file(
      dir, "p.yaml",
      "ekf:\n  ros__parameters:\n    odom0: /odom\n    initial_estimate_covariance: " + flow_list(m, 34) +
          "\n");
  const RlParams p = odotune::rlnode::read_rl_params(f);
  EXPECT_EQ(p.initial_estimate_covariance(0, 1), 0.5);
  EXPECT_EQ(p.initial_estimate_covariance(1, 0), 0.25);
  EXPECT_EQ(p.initial_estimate_covariance(0, 14), 0.125);
  EXPECT_EQ(p.initial_estimate_covariance(14, 0), 0.0);
  EXPECT_EQ(p.initial_estimate_covariance(7, 7), 1.0);
}

TEST(RlParams, DifferentialWinsOverRelative) {
  TempDir dir;
  const fs::path f = write_file(dir, "p.yaml", R"(ekf:
  odom0: /a
  odom0_differential: true
  odom0_relative: true
  odom1: /b
  odom1_relative: true
)");
  const RlParams p = odotune::rlnode::read_rl_params(f);
  ASSERT_EQ(p.sensors.size(), 2U);
  EXPECT_TRUE(p.sensors[0].differential);
  EXPECT_FALSE(p.sensors[0].relative);
  EXPECT_FALSE(p.sensors[1].differential);
  EXPECT_TRUE(p.sensors[1].relative);
}

// Keys robot_localization does not read (not its parameters, or inputs past the
// first gap of their numbering) are left out and noted with their line, as the
// node ignores them; a key given twice with one value is read once and noted,
// with two values refused.
TEST(RlParams, NotesKeysTheNodeDoesNotReadAndLeavesThemOut) {
  TempDir dir;
  const fs::path f = write_file(dir, "gap.yaml", "ekf:\n  odom0: /a\n  odom1: /b\n  odom3: /d\n  imu0: /imu\n");
  const RlParams p = odotune::rlnode::read_rl_params(f);
  EXPECT_EQ(p.sensors.size(), 3u);  // odom0, odom1, imu0
  ASSERT_EQ(p.notes.size(), 1u);
  EXPECT_EQ(p.notes[0].rfind(f.string() + ":4: odom3 is not read by robot_localization either", 0), 0U)
      << p.notes[0];
  EXPECT_NE(p.notes[0].find("odom2 is missing"), std::string::npos) << p.notes[0];

  const fs::path g = write_file(dir, "p.yaml", R"(# comment
ekf_filter_node:
  ros__parameters:
    odom0: /odom
    odom0_confg: [true]
    silent_tf_failure: false
    twist0: /t
    twist0_differential: false
nav:
  yaw_offset: 0.0
  zero_altitud: true
)");
  const RlParams q = odotune::rlnode::read_rl_params(g);
  ASSERT_EQ(q.notes.size(), 4u);
  EXPECT_EQ(q.notes[0].rfind(g.string() + ":5: 'odom0_confg' of ekf_filter_node is not one of", 0), 0U)
      << q.notes[0];
  EXPECT_NE(q.notes[1].find(":6: 'silent_tf_failure'"), std::string::npos) << q.notes[1];
  EXPECT_NE(q.notes[2].find(":8: 'twist0_differential'"), std::string::npos) << q.notes[2];
  EXPECT_NE(q.notes[3].find(":11: 'zero_altitud' of nav"), std::string::npos) << q.notes[3];
  EXPECT_EQ(q.sensors[0].config, UpdateMask{});  // the misspelt config is not read
  // the same replay as without the keys the node does not read
  const fs::path clean = write_file(dir, "clean.yaml",
                                    "ekf_filter_node:\n  ros__parameters:\n    odom0: /odom\n"
                                    "    twist0: /t\nnav:\n  yaw_offset: 0.0\n");
  const RlParams c = odotune::rlnode::read_rl_params(clean);
  EXPECT_EQ(c.sensors.size(), q.sensors.size());
  EXPECT_EQ(c.process_noise_covariance, q.process_noise_covariance);

  const fs::path same = write_file(dir, "same.yaml",
                                   "ekf:\n  odom0: /o\n  two_d_mode: true\n  two_d_mode: true\n");
  const RlParams s = odotune::rlnode::read_rl_params(same);
  EXPECT_TRUE(s.two_d_mode);
  ASSERT_EQ(s.notes.size(), 1u);
  EXPECT_NE(s.notes[0].find(":4: two_d_mode is given twice with the same value (first at line 3)"),
            std::string::npos)
      << s.notes[0];
  const fs::path differ = write_file(dir, "differ.yaml",
                                     "ekf:\n  odom0: /o\n  two_d_mode: true\n  two_d_mode: false\n");
  const std::string e = read_error(differ);
  EXPECT_EQ(e.rfind(differ.string() +
                        ":4: two_d_mode is given twice with different values (true at line 3, false here)",
                    0),
            0U)
      << e;
}

TEST(RlParams, RefusesValuesTheReplayDoesNotReproduce) {
  TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"  smooth_lagged_data: true\n  use_control: true\n  control_config: [true, false, false, false, false, "
       "false]\n",
       "smooth_lagged_data: true with use_control: true is not reproduced"},
      {"  disabled_at_startup: true\n", "disabled_at_startup: true is not reproduced"},
      {"  filter_type: ukf\n", "filter_type: ukf is not reproduced"},
  };
  for (const auto& [line, message] : cases) {
    const fs::path f = write_file(dir, "p.yaml", "ekf:\n  odom0: /o\n" + line);
    const std::string e = read_error(f);
    EXPECT_EQ(e.rfind(f.string() + ":3: " + message, 0), 0U) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  const fs::path nav = write_file(dir, "nav.yaml",
                                  "ekf:\n  odom0: /o\nnavsat:\n  yaw_offset: 0.0\n  wait_for_datum: true\n");
  EXPECT_EQ(read_error(nav).rfind(nav.string() + ":5: wait_for_datum: true without a datum", 0), 0U)
      << read_error(nav);
  // the same keys at their harmless values
  const fs::path ok = write_file(dir, "ok.yaml", R"(ekf:
  odom0: /o
  smooth_lagged_data: false
  history_length: 1.0
  use_control: false
  control_config: [true, false, false, false, false, true]
  disabled_at_startup: false
  reset_on_time_jump: false
  odom0_pose_use_child_frame: false
  filter_type: ekf
  publish_tf: true
  odom0_queue_size: 2
  odom0_nodelay: true
)");
  EXPECT_EQ(read_error(ok), "");
}

// use_control as ros_filter.cpp's loadParams reads it, ROS 1 and ROS 2.
TEST(RlParams, ReadsUseControl) {
  TempDir dir;
  const RlParams r1 = odotune::rlnode::read_rl_params(write_file(dir, "r1.yaml", R"(ekf:
  odom0: /o
  sensor_timeout: 0.25
  use_control: true
  stamped_control: true
  control_config: [true, false, false, false, false, true]
  acceleration_limits: [1.3, 0.0, 0.0, 0.0, 0.0, 3.4]
  acceleration_gains: [0.8, 0.0, 0.0, 0.0, 0.0, 0.9]
)"));
  ASSERT_TRUE(r1.control.enabled);
  EXPECT_TRUE(r1.control.stamped);
  EXPECT_EQ(r1.control.filter.timeout_ns, 250'000'000);  // ROS 1: sensor_timeout by default
  EXPECT_EQ(r1.control.filter.timeout_rule, odotune::filters::rl::ControlTimeout::absolute);
  EXPECT_TRUE(r1.control.filter.update[0] && r1.control.filter.update[5] && !r1.control.filter.update[1]);
  EXPECT_DOUBLE_EQ(r1.control.filter.deceleration_limits[5], 3.4);  // the acceleration's when missing
  EXPECT_DOUBLE_EQ(r1.control.filter.deceleration_gains[0], 0.8);
  // ROS 2: control_timeout 0.0 by default, the forward rule, no stamped_control,
  // missing gains taken as 1.0 with a note.
  const RlParams r2 = odotune::rlnode::read_rl_params(write_file(dir, "r2.yaml", R"(ekf:
  ros__parameters:
    odom0: /o
    use_control: true
    stamped_control: true
    control_config: [true, true, false, false, false, true]
    acceleration_limits: [2.7, 1.5, 0.0, 0.0, 0.0, 5.7]
)"));
  ASSERT_TRUE(r2.control.enabled);
  EXPECT_FALSE(r2.control.stamped);
  EXPECT_EQ(r2.control.filter.timeout_ns, 0);
  EXPECT_EQ(r2.control.filter.timeout_rule, odotune::filters::rl::ControlTimeout::forward);
  EXPECT_DOUBLE_EQ(r2.control.filter.acceleration_gains[1], 1.0);
  std::string notes;
  for (const std::string& n : r2.notes) notes += n + "\n";
  EXPECT_NE(notes.find("stamped_control is not read by ROS 2's node"), std::string::npos) << notes;
  EXPECT_NE(notes.find("without acceleration_gains"), std::string::npos) << notes;
}

// Where the node turns the control term off, the replay does too and says so.
TEST(RlParams, UseControlTurnedOffAsTheNodeDoes) {
  TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "control_config is missing"},
      {"  control_config: [true, false]\n", "control_config has 2 entries, not 6"},
      {"  control_config: [true, false, false, false, false, false]\n  acceleration_limits: [1.0]\n",
       "acceleration_limits has 1 entries, not 6"},
      {"  control_config: [false, false, false, false, false, false]\n", "leaves no member controlled"},
      // the IMU's fused x acceleration takes vx out
      {"  control_config: [true, false, false, false, false, false]\n  imu0: /i\n  imu0_config: [false, false, "
       "false, false, false, false, false, false, false, false, false, false, true, false, false]\n",
       "leaves no member controlled"},
  };
  for (const auto& [keys, why] : cases) {
    const RlParams p = odotune::rlnode::read_rl_params(
        write_file(dir, "p.yaml", "ekf:\n  odom0: /o\n  use_control: true\n" + keys));
    EXPECT_FALSE(p.control.enabled) << keys;
    std::string notes;
    for (const std::string& n : p.notes) notes += n + "\n";
    EXPECT_NE(notes.find(why), std::string::npos) << notes;
  }
  // ukf_node: computed, never applied
  const RlParams u = odotune::rlnode::read_rl_params(
      write_file(dir, "u.yaml",
                 "ukf:\n  odom0: /o\n  use_control: true\n  "
                 "control_config: [true, false, false, false, false, true]\n"));
  EXPECT_FALSE(u.control.enabled);
  std::string u_notes;
  for (const std::string& n : u.notes) u_notes += n + "\n";
  EXPECT_NE(u_notes.find("does not apply it"), std::string::npos) << u_notes;
  // a negative gain is refused, in one line
  const fs::path bad = write_file(dir, "bad.yaml",
                                  "ekf:\n  odom0: /o\n  use_control: true\n  control_config: "
                                  "[true, false, false, false, false, true]\n  acceleration_gains: "
                                  "[-1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n");
  const std::string e = read_error(bad);
  EXPECT_NE(e.find("acceleration_gains[0] = -1"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

TEST(RlParams, RefusesABadCovarianceSize) {
  TempDir dir;
  const fs::path f = write_file(
      dir, "p.yaml",
      "ekf:\n  odom0: /o\n  process_noise_covariance: " + flow_list(std::vector<double>(14, 0.1), 10) + "\n");
  EXPECT_EQ(read_error(f), f.string() +
                               ":3: process_noise_covariance has 14 entries, expected 15 (the diagonal) or 225 "
                               "(the matrix)");
  const fs::path g = write_file(dir, "q.yaml", "ekf:\n  odom0: /o\n  odom0_config: [true, false]\n");
  EXPECT_EQ(read_error(g).rfind(g.string() + ":3: odom0_config has 2 entries, expected 15 booleans", 0), 0U);
}

TEST(RlParams, RefusesWrongTypesOnOneLine) {
  TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"  two_d_mode: maybe\n", ":3: two_d_mode must be true or false, got 'maybe'"},
      {"  frequency: fast\n", ":3: frequency must be a number, got 'fast'"},
      {"  frequency: -5.0\n", ":3: frequency is -5, expected a rate > 0 [Hz]"},
      {"  sensor_timeout: -0.1\n", ":3: sensor_timeout is -0.1, expected a time >= 0 [s]"},
      {"  odom0_config: [true, 3, false]\n", ":3: odom0_config entry 2 must be true or false, got '3'"},
      {"  process_noise_covariance: 0.1\n",
       ":3: process_noise_covariance must be a list of numbers, got '0.1'"},
      {"  odom0_pose_rejection_threshold: -1\n", ":3: odom0_pose_rejection_threshold is -1, expected"},
      {"  frequency: \"30\"\n", ":3: frequency must be a number, got the quoted string \"30\""},
      {"  initial_state: [1.0, 2.0]\n", ":3: initial_state has 2 entries, expected 15"},
      {"  odom0: /p\n", ":3: odom0 is given twice with different values (/o at line 2, /p here)"},
  };
  for (const auto& [line, message] : cases) {
    const fs::path f = write_file(dir, "p.yaml", "ekf:\n  odom0: /o\n" + line);
    const std::string e = read_error(f);
    EXPECT_EQ(e.rfind(f.string() + message, 0), 0U) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  // ROS 2 declares frequency a double and refuses an integer
  const fs::path r2 = write_file(dir, "r2.yaml",
                                 "ekf:\n  ros__parameters:\n    odom0: /o\n    frequency: 30\n");
  EXPECT_EQ(read_error(r2).rfind(r2.string() + ":4: frequency is the integer 30, which ROS 2 refuses", 0), 0U)
      << read_error(r2);
  const fs::path bad = write_file(dir, "bad.yaml", "ekf:\n  odom0: [/o\n  frequency: 3\n");
  EXPECT_EQ(read_error(bad).rfind(bad.string() + ":", 0), 0U);
  EXPECT_EQ(read_error(bad).find('\n'), std::string::npos);
  EXPECT_EQ(read_error(dir / "missing.yaml").rfind((dir / "missing.yaml").string() + ": cannot open", 0), 0U);
}

TEST(RlParams, PicksTheEkfSectionByName) {
  TempDir dir;
  const fs::path f = write_file(dir, "dual.yaml", R"(ekf_odom:
  ros__parameters:
    frequency: 30.0
    odom0: /wheels
ekf_map:
  ros__parameters:
    frequency: 10.0
    odom0: /wheels
    odom1: /odometry/gps
other:
  ros__parameters:
    final_x: 1.0
)");
  const std::string e = read_error(f);
  EXPECT_EQ(e.rfind(f.string() + ":5: several ekf_node sections (ekf_odom, ekf_map)", 0), 0U) << e;
  const RlParams p = odotune::rlnode::read_rl_params(f, "ekf_map");
  EXPECT_EQ(p.node_name, "ekf_map");
  EXPECT_EQ(p.frequency_hz, 10.0);
  EXPECT_EQ(p.sensors.size(), 2U);
  EXPECT_EQ(odotune::rlnode::read_rl_params(f, "/ekf_odom").frequency_hz, 30.0);
  EXPECT_NE(read_error(f, "ekf_x").find("no section 'ekf_x', expected one of ekf_odom, ekf_map, other"),
            std::string::npos);
  const fs::path none = write_file(dir, "none.yaml", "a:\n  frequency: 3.0\n");
  EXPECT_NE(read_error(none).find(":1: no ekf_node section"), std::string::npos) << read_error(none);
}

TEST(RlParams, AcceptsWildcardNodeName) {
  TempDir dir;
  const fs::path f = write_file(dir, "w.yaml",
                                "/**:\n  ros__parameters:\n    odom0: /o\n    frequency: 20.0\n");
  const RlParams p = odotune::rlnode::read_rl_params(f);
  EXPECT_TRUE(p.ros2);
  EXPECT_EQ(p.node_name, "/**");
  EXPECT_EQ(p.frequency_hz, 20.0);
}

TEST(RlParamsWrite, SameFormKeepsTheUsersFile) {
  TempDir dir;
  const RlParams p = odotune::rlnode::read_rl_params(kHusky);
  const RlParamsUpdate u = husky_update();
  const std::string out = odotune::rlnode::write_rl_params(kHusky, p, u, true, "tuned by odotune\nsecond line");
  const std::string original = read_file(kHusky);
  // the header, then the user's file: every comment line and untouched key kept
  EXPECT_EQ(out.rfind("# tuned by odotune\n# second line\n# A robot_localization parameter file", 0), 0U);
  std::istringstream lines(original);
  for (std::string line; std::getline(lines, line);) {
    if (line.find('#') != std::string::npos || line.find("_config") != std::string::npos) {
      EXPECT_NE(out.find(line + "\n"), std::string::npos) << line;
    }
  }
  // the covariance as 15 rows, inserted at the section's indentation
  const std::size_t at = out.find("\n    process_noise_covariance: [");
  ASSERT_NE(at, std::string::npos) << out;
  const std::size_t end = out.find(']', at);
  EXPECT_EQ(std::count(out.begin() + static_cast<long>(at) + 1, out.begin() + static_cast<long>(end), '\n'),
            14);
  EXPECT_NE(out.find("    imu0_linear_acceleration_rejection_threshold: 0.7999999999999999\n"),
            std::string::npos);
  EXPECT_EQ(out.find("odom0_pose_rejection_threshold"), std::string::npos);  // kNoRejection: left out
  EXPECT_NE(out.find(fmt::format("    yaw_offset: {}\n", *u.navsat_yaw_offset)), std::string::npos);
  const fs::path f = write_file(dir, "tuned.yaml", out);
  const RlParams back = odotune::rlnode::read_rl_params(f);
  EXPECT_TRUE(back.ros2);
  EXPECT_EQ(back.node_name, "ekf_filter_node");
  expect_updated(p, u, back);
}

TEST(RlParamsWrite, SameFormEditsValuesWhereTheyStand) {
  TempDir dir;
  const fs::path f = write_file(dir, "ros1.yaml", kRos1File);
  const RlParams p = odotune::rlnode::read_rl_params(f);
  RlParamsUpdate u;
  u.process_noise_covariance = tuned_matrix(2.0);
  u.initial_estimate_covariance = odotune::rlnode::default_initial_estimate_covariance();
  u.rejection_thresholds = {{"odom0", {2.25, kNoRejection, kNoRejection}}};
  u.navsat_yaw_offset = 1.5;
  const std::string out = odotune::rlnode::write_rl_params(f, p, u, false, "");
  EXPECT_EQ(out.rfind("# my robot, ROS 1\nekf_se:\n  frequency: 50   # Hz\n", 0), 0U) << out;
  EXPECT_NE(out.find("  odom0_pose_rejection_threshold: 2.25   # keep me\n"), std::string::npos) << out;
  EXPECT_EQ(out.find("odom0_twist_rejection_threshold"), std::string::npos) << out;
  EXPECT_NE(out.find("  # the diagonal\n  process_noise_covariance: [0.1,"), std::string::npos) << out;
  EXPECT_EQ(out.find("0.1, 0.1"), std::string::npos);  // the old value is gone
  EXPECT_NE(out.find("\n  odom1: /odometry/gps\n"), std::string::npos);
  EXPECT_NE(out.find("  yaw_offset: 1.5\n"), std::string::npos);
  const RlParams back = odotune::rlnode::read_rl_params(write_file(dir, "tuned.yaml", out));
  EXPECT_FALSE(back.ros2);
  u.rejection_thresholds = {{"odom0", {2.25, kNoRejection, kNoRejection}}};
  expect_updated(p, u, back);
}

TEST(RlParamsWrite, ConvertsRos2ToRos1AndBack) {
  TempDir dir;
  const RlParams p = odotune::rlnode::read_rl_params(kHusky);
  const RlParamsUpdate u = husky_update();
  const std::string ros1 = odotune::rlnode::write_rl_params(kHusky, p, u, false, "tuned");
  EXPECT_EQ(ros1.rfind("# tuned\n# Converted from the ROS 2 form of husky_ekf.yaml", 0), 0U) << ros1;
  EXPECT_EQ(ros1.find("ros__parameters"), std::string::npos);
  const fs::path f1 = write_file(dir, "ros1.yaml", ros1);
  const RlParams back1 = odotune::rlnode::read_rl_params(f1);
  EXPECT_FALSE(back1.ros2);
  EXPECT_EQ(back1.node_name, "ekf_filter_node");
  expect_updated(p, u, back1);
  // and back to ROS 2, with nothing to change
  const std::string ros2 = odotune::rlnode::write_rl_params(f1, back1, {}, true, "");
  const RlParams back2 = odotune::rlnode::read_rl_params(write_file(dir, "ros2.yaml", ros2));
  EXPECT_TRUE(back2.ros2);
  expect_same(back1, back2);
}

TEST(RlParamsWrite, ConvertsRos1ToRos2WithDoubles) {
  TempDir dir;
  const fs::path f = write_file(dir, "ros1.yaml", kRos1File);
  const RlParams p = odotune::rlnode::read_rl_params(f);
  RlParamsUpdate u;
  u.rejection_thresholds = {{"imu0", {kNoRejection, 0.5, 4.0}}};
  const std::string out = odotune::rlnode::write_rl_params(f, p, u, true, "");
  EXPECT_NE(out.find("frequency: 50.0\n"), std::string::npos) << out;  // ROS 2 refuses the integer 50
  EXPECT_NE(out.find("ros__parameters"), std::string::npos);
  EXPECT_EQ(out.find("# my robot"), std::string::npos);
  const RlParams back = odotune::rlnode::read_rl_params(write_file(dir, "ros2.yaml", out));
  EXPECT_TRUE(back.ros2);
  EXPECT_EQ(back.node_name, "ekf_se");
  RlParams want = p;
  want.sensors[2].twist_rejection_threshold = 0.5;  // imu0 (after odom0, odom1)
  want.sensors[2].accel_rejection_threshold = 4.0;
  ASSERT_EQ(want.sensors[2].name, "imu0");
  expect_same(want, back);
}

TEST(RlParamsWrite, ConvertsAFlatRos1FileToAWildcardSection) {
  TempDir dir;
  const fs::path f = write_file(dir, "flat.yaml",
                                "frequency: 40\nodom0: /o\nodom0_config: [true, true, false, "
                                "false, false, false, false, false, false, false, false, false, "
                                "false, false, false]\n");
  const RlParams p = odotune::rlnode::read_rl_params(f);
  RlParamsUpdate u;
  u.process_noise_covariance = tuned_matrix(0.5);
  const fs::path f2 = write_file(dir, "ros2.yaml", odotune::rlnode::write_rl_params(f, p, u, true, ""));
  const RlParams back = odotune::rlnode::read_rl_params(f2);
  EXPECT_EQ(back.node_name, "/**");
  EXPECT_TRUE(back.process_noise_covariance == *u.process_noise_covariance);
  EXPECT_EQ(back.sensors.at(0).config, mask({0, 1}));
  const RlParams flat = odotune::rlnode::read_rl_params(
      write_file(dir, "flat2.yaml", odotune::rlnode::write_rl_params(f2, back, {}, false, "")));
  EXPECT_EQ(flat.node_name, "");
  expect_same(back, flat);
}

TEST(RlParamsWrite, RefusesAnUnknownInput) {
  RlParamsUpdate u;
  u.rejection_thresholds = {{"odom7", {1.0, 1.0, kNoRejection}}};
  const RlParams p = odotune::rlnode::read_rl_params(kHusky);
  EXPECT_THROW(odotune::rlnode::write_rl_params(kHusky, p, u, true, ""), std::invalid_argument);
  u.rejection_thresholds = {{"odom0", {1.0, 1.0, 2.0}}};  // odomN has no acceleration threshold
  EXPECT_THROW(odotune::rlnode::write_rl_params(kHusky, p, u, true, ""), std::invalid_argument);
}

TEST(RlParamsWrite, ReplacesAnAliasedValueAtItsKey) {
  TempDir dir;
  const fs::path f = write_file(dir, "alias.yaml", R"(shared: &five 5.0
ekf:
  odom0: /o
  odom0_pose_rejection_threshold: *five   # from shared
  odom0_twist_rejection_threshold: *five
)");
  const RlParams p = odotune::rlnode::read_rl_params(f);
  EXPECT_EQ(p.sensors.at(0).twist_rejection_threshold, 5.0);
  RlParamsUpdate u;
  u.rejection_thresholds = {{"odom0", {2.0, 5.0, kNoRejection}}};
  const std::string out = odotune::rlnode::write_rl_params(f, p, u, false, "");
  EXPECT_EQ(out.rfind("shared: &five 5.0\n", 0), 0U) << out;  // the anchor is left alone
  EXPECT_NE(out.find("  odom0_pose_rejection_threshold: 2.0   # from shared\n"), std::string::npos) << out;
  const RlParams back = odotune::rlnode::read_rl_params(write_file(dir, "out.yaml", out));
  EXPECT_EQ(back.sensors.at(0).pose_rejection_threshold, 2.0);
  EXPECT_EQ(back.sensors.at(0).twist_rejection_threshold, 5.0);
}

// ekf_node or ukf_node: a ukf_filter_node section (as robot_localization's
// ukf.yaml names it; the constants left at ukf_node's defaults), a section with
// ukf_node's keys, a file that does not say (the caller's choice, else the
// EKF), and the refusals.
TEST(RlParams, PicksTheUkfFromTheSectionOrItsKeys) {
  namespace rl = odotune::filters::rl;
  TempDir dir;
  const fs::path named = write_file(dir, "u.yaml", "ukf_filter_node:\n  ros__parameters:\n    odom0: /o\n");
  const RlParams shipped = odotune::rlnode::read_rl_params(named);
  EXPECT_EQ(shipped.filter, rl::RlFilterType::ukf);
  EXPECT_EQ(shipped.ukf.alpha, 0.001);
  EXPECT_EQ(shipped.ukf.kappa, 0.0);
  EXPECT_EQ(shipped.ukf.beta, 2.0);

  const fs::path keyed = write_file(dir, "k.yaml", "ekf:\n  odom0: /o\n  alpha: 0.3\n  kappa: 1.0\n");
  const RlParams k = odotune::rlnode::read_rl_params(keyed);
  EXPECT_EQ(k.filter, rl::RlFilterType::ukf);
  EXPECT_EQ(k.ukf.alpha, 0.3);
  EXPECT_EQ(k.ukf.kappa, 1.0);
  EXPECT_EQ(k.ukf.beta, 2.0);

  const fs::path flat = write_file(dir, "f.yaml", "frequency: 30.0\nodom0: /o\n");
  EXPECT_EQ(odotune::rlnode::read_rl_params(flat).filter, rl::RlFilterType::ekf);
  EXPECT_EQ(odotune::rlnode::read_rl_params(flat, "", rl::RlFilterType::ukf).filter, rl::RlFilterType::ukf);

  try {
    odotune::rlnode::read_rl_params(keyed, "", rl::RlFilterType::ekf);
    ADD_FAILURE() << "alpha with --filter ekf was read";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind(keyed.string() + ":3: alpha is read by ukf_node only", 0), 0U)
        << e.what();
  }
  const fs::path bad = write_file(dir, "b.yaml", "ukf_filter_node:\n  odom0: /o\n  alpha: 0.0\n");
  EXPECT_EQ(read_error(bad).rfind(bad.string() + ":3: ukf_node's alpha = 0, expected > 0", 0), 0U)
      << read_error(bad);
}

// ROS 2's namespaced form (NAMESPACE: {NODE: {ros__parameters: …}}), as
// GISNav's and Locus Robotics' files have it: each node a section named
// NAMESPACE/NODE, picked by either name; written back in place.
TEST(RlParams, ReadsNodesInsideANamespace) {
  const fs::path configs = fs::path(ODOTUNE_SHARED_DIR) / "data/real/robot_localization_configs";
  const RlParams g = odotune::rlnode::read_rl_params(
      configs / "hmakelin__gisnav__ros_gisnav_launch_params_ekf_local_node.yaml");
  EXPECT_EQ(g.node_name, "robot_localization/ekf_local_node");
  EXPECT_TRUE(g.ros2);
  EXPECT_FALSE(g.sensors.empty());
  const fs::path two = configs /
                       "locusrobotics__roscon-uk-2025-se-workshop@answers__task4_config_two_tier_gps.yaml";
  EXPECT_NE(read_error(two).find("several ekf_node sections (r2d2/ekf_node_tier1, r2d2/ekf_node_tier2)"),
            std::string::npos)
      << read_error(two);
  // each tier found by either name, each with its own smooth_lagged_data history
  const RlParams t1 = odotune::rlnode::read_rl_params(two, "ekf_node_tier1");
  const RlParams t2 = odotune::rlnode::read_rl_params(two, "r2d2/ekf_node_tier2");
  EXPECT_TRUE(t1.smooth_lagged_data && t2.smooth_lagged_data);
  EXPECT_EQ(t1.history_length_ns, 1'000'000'000);
  EXPECT_EQ(t2.history_length_ns, 400'000'000);

  TempDir dir;
  const fs::path f = write_file(dir, "ns.yaml",
                                "/**:\n  ekf_filter:\n    ros__parameters:\n      odom0: /o\n"
                                "      odom0_config: [true, true, false, false, false, false, "
                                "false, false, false, false, false, false, false, false, false]\n");
  const RlParams p = odotune::rlnode::read_rl_params(f);
  EXPECT_EQ(p.node_name, "/**/ekf_filter");
  RlParamsUpdate u;
  u.process_noise_covariance = Matrix15::Identity() * 0.5;
  const fs::path out = write_file(dir, "out.yaml", odotune::rlnode::write_rl_params(f, p, u, true, "tuned"));
  EXPECT_EQ(odotune::rlnode::read_rl_params(out).process_noise_covariance, Matrix15::Identity() * 0.5);
  EXPECT_THROW(odotune::rlnode::write_rl_params(f, p, u, false, "tuned"), std::invalid_argument);
}

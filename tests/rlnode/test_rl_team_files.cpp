// Teams' own robot_localization files on robot_localization's own bags
// (../shared/data/real/robot_localization_configs and _bags): Clearpath's
// Husky files, ROS 1 and ROS 2, replayed on test1 (the ROS 2 one through
// --remap), and the keys that change nothing, each shown to leave the
// replay's output identical.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/rlnode/params.h>
#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>

#include "support/rl_test1.h"
#include "support/temp_dir.h"

namespace rl = odotune::filters::rl;
using namespace odotune::rlnode;

namespace {

const std::filesystem::path kTeamShared = std::filesystem::path(ODOTUNE_SHARED_DIR) / "data/real";
const std::filesystem::path kTeamConfigs = kTeamShared / "robot_localization_configs";
const std::filesystem::path kTeamBags = kTeamShared / "robot_localization_bags";

ReplayOutput team_replay(const RlParams& p, const std::filesystem::path& bag, const RecordingOptions& o) {
  const Recording rec = load_recording(bag, p, o);
  return replay(rec, make_schedule(rec), settings_of(rec.params));
}

}  // namespace

// Clearpath's husky_control localization.yaml, ROS 1 (noetic) and ROS 2
// (humble): the ROS 1 file's topics are test1's; the ROS 2 file subscribes to
// `odom` and is refused without --remap odom=/husky_velocity_controller/odom.
// Both fuse the wheels' velocities and the IMU's differential attitude, so
// they dead-reckon the 395 s drive: the whole bag is processed, the estimate
// stays finite, and the two forms differ only in predict_to_current_time.
TEST(RlTeamFiles, ClearpathHuskyFilesReplayOnTest1) {
  const RlParams ros1 = read_rl_params(kTeamConfigs / "husky__husky__husky_control_config_localization.yaml");
  const RlParams ros2 = read_rl_params(kTeamConfigs /
                                       "husky__husky@humble-devel__husky_control_config_localization.yaml");
  EXPECT_FALSE(ros1.ros2);
  EXPECT_TRUE(ros2.ros2);
  EXPECT_TRUE(ros1.predict_to_current_time);
  EXPECT_FALSE(ros2.predict_to_current_time);
  const auto bag = kTeamBags / "test1.bag";
  RecordingOptions o = odotune::testing_support::test1_imu_mounting();
  try {
    load_recording(bag, ros2, o);
    ADD_FAILURE() << "the ROS 2 file's odom topic is not test1's";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("odom0 topic /odom is not in the bag"), std::string::npos) << e.what();
  }
  const ReplayOutput a = team_replay(ros1, bag, o);
  o.remap["odom"] = "/husky_velocity_controller/odom";
  const ReplayOutput b = team_replay(ros2, bag, o);
  for (const ReplayOutput* out : {&a, &b}) {
    EXPECT_TRUE(out->finite);
    EXPECT_EQ(out->rejected, 0);
    // 3 952 odometry and 11 865 IMU messages, the IMU's in two parts
    // (attitude, rates) at most.
    EXPECT_GT(out->processed, 3952 + 11865 - 10);
    EXPECT_GT(out->final_state.head<2>().norm(), 10.0) << "the robot drove away from its start";
  }
  EXPECT_NE(a.final_state, b.final_state) << "predict_to_current_time must change the output";
  // With predict_to_current_time added, the ROS 2 file is the ROS 1 one: the
  // same replay, bit for bit.
  odotune::testing_support::TempDir dir("rl-husky-forms");
  std::ifstream in(kTeamConfigs / "husky__husky@humble-devel__husky_control_config_localization.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string at = "    two_d_mode: true\n";
  ASSERT_NE(text.find(at), std::string::npos);
  text.insert(text.find(at) + at.size(), "    predict_to_current_time: true\n");
  std::ofstream(dir.path() / "husky.yaml") << text;
  const ReplayOutput c = team_replay(read_rl_params(dir.path() / "husky.yaml"), bag, o);
  EXPECT_EQ(a.final_state, c.final_state);
  EXPECT_EQ(a.final_cov, c.final_cov);
}

// Each key that the node reads but that cannot change a replay is accepted,
// listed in one note, and leaves the output of robot_localization's bag2
// configuration on test2 bit for bit as it was.
TEST(RlTeamFiles, KeysWithoutEffectLeaveTheReplayIdentical) {
  odotune::testing_support::TempDir dir("rl-no-effect");
  const std::string base = R"(bag2:
  frequency: 50.0
  sensor_timeout: 0.1
  odom0: /jackal_velocity_controller/odom
  imu0: /imu/data
  odom0_config: [false, false, false, false, false, false, true, true, true, false, false, true, false, false, false]
  imu0_config: [false, false, false, true, true, true, false, false, false, true, true, true, true, true, true]
  imu0_remove_gravitational_acceleration: true
)";
  const std::vector<std::string> keys = {"reset_on_time_jump: true",
                                         "use_sim_time: true",
                                         "clear_params: true",
                                         "publish_tf: false",
                                         "publish_acceleration: true",
                                         "permit_corrected_publication: true",
                                         "print_diagnostics: true",
                                         "debug: true",
                                         "debug_out_file: /tmp/x.txt",
                                         "transform_time_offset: 0.5",
                                         "transform_timeout: 0.5",
                                         "tf_prefix: robot",
                                         "base_link_frame_output: base_footprint",
                                         "invert_tf: true",
                                         "history_length: 2.0",
                                         "odom0_queue_size: 1",
                                         "imu0_queue_size: 50",
                                         "odom0_nodelay: true",
                                         "control_timeout: 0.5",
                                         "control_config: [true, false, false, false, false, true]",
                                         "use_control: false"};
  auto run = [&](const std::string& extra) {
    const auto f = dir.path() / "p.yaml";
    std::ofstream(f) << base << (extra.empty() ? "" : "  " + extra + "\n");
    const RlParams p = read_rl_params(f);
    return std::make_pair(p, team_replay(p, kTeamBags / "test2.bag", {}));
  };
  const auto [plain, reference] = run("");
  for (const std::string& k : keys) {
    const auto [p, out] = run(k);
    EXPECT_EQ(out.final_state, reference.final_state) << k;
    EXPECT_EQ(out.final_cov, reference.final_cov) << k;
    EXPECT_EQ(out.processed, reference.processed) << k;
    if (k == "use_control: false") continue;  // the default: not listed
    const std::string name = k.substr(0, k.find(':'));
    int listed = 0;
    for (const std::string& n : p.notes)
      listed += n.find(name + " change nothing in a replay") != std::string::npos;
    EXPECT_EQ(listed, 1) << k;
  }
}

// Every filter section of the 31 teams' files loads, each key reproduced, of
// no effect or not read by robot_localization either; the four
// navsat-only files have no filter section (they go with --navsat-params).
// The table of docs/robot-localization/teams-files.md is this, key by key.
TEST(RlTeamFiles, EveryTeamFileLoadsOrIsRefusedByName) {
  int files = 0, sections = 0, loaded = 0, navsat_only = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kTeamConfigs)) {
    if (entry.path().extension() != ".yaml") continue;
    ++files;
    std::vector<std::string> nodes{""};
    try {
      read_rl_params(entry.path());
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      const std::string several = "several ekf_node sections (";
      if (const auto at = what.find(several); at != std::string::npos) {
        nodes.clear();
        std::string list = what.substr(at + several.size(), what.find(')', at) - at - several.size());
        for (std::size_t start = 0; start <= list.size();) {
          const std::size_t comma = std::min(list.find(", ", start), list.size());
          nodes.push_back(list.substr(start, comma - start));
          start = comma + 2;
        }
      }
    }
    for (const std::string& node : nodes) {
      ++sections;
      try {
        const RlParams p = read_rl_params(entry.path(), node);
        ++loaded;
        EXPECT_FALSE(p.keys.empty()) << entry.path();
        for (const KeyReport& k : p.keys) EXPECT_GT(k.line, 0) << k.key;
      } catch (const std::invalid_argument& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("no ekf_node section"), std::string::npos)
            << entry.path().filename() << " " << node << ": " << what;
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        const RlParams n = read_navsat_params(entry.path());
        EXPECT_TRUE(n.navsat.present);
        EXPECT_FALSE(n.keys.empty());
        ++navsat_only;
      }
    }
  }
  EXPECT_EQ(files, 31);
  EXPECT_EQ(sections, 37);
  EXPECT_EQ(loaded, 33);
  EXPECT_EQ(navsat_only, 4);
}

// Heron's team keeps navsat_transform_node's parameters in a file of their
// own: --navsat-params reads it beside the filter's (its keys reported with
// that file's name); a filter file that has a navsat section already is refused.
TEST(RlTeamFiles, NavsatParamsFromTheirOwnFile) {
  const auto filter = kTeamConfigs / "heron__heron__heron_control_config_robot_localization.yaml";
  const auto navsat = kTeamConfigs / "heron__heron__heron_control_config_navsat_config.yaml";
  EXPECT_FALSE(read_rl_params(filter).navsat.present);
  const RlParams p = read_rl_params(filter, "", std::nullopt, navsat);
  ASSERT_TRUE(p.navsat.present);
  EXPECT_EQ(p.navsat.frequency_hz, 20.0);  // ROS 1: an integer is a number
  EXPECT_FALSE(p.navsat.zero_altitude);
  int navsat_keys = 0;
  for (const KeyReport& k : p.keys) navsat_keys += k.section.find("navsat_config.yaml") != std::string::npos;
  EXPECT_EQ(navsat_keys, 8);
  const auto dual = kTeamConfigs / "cra-ros-pkg__robot_localization__params_dual_ekf_navsat_example.yaml";
  try {
    read_rl_params(dual, "ekf_filter_node_map", std::nullopt, navsat);
    ADD_FAILURE() << "two navsat sections must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--navsat-params"), std::string::npos) << e.what();
  }
}

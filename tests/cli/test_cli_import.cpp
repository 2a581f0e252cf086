// `odotune import ...` end to end: runs the built binary on the real datasets
// and on a missing file, and reads back what it wrote.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <odotune/tracks/track_io.h>

#include "support/cli_runner.h"

namespace odotune::cli {
namespace {

namespace fs = std::filesystem;

const fs::path kReal = fs::path(ODOTUNE_SHARED_DIR) / "data" / "real";

struct ProcResult {
  int exit_code;
  std::string out, err;
};

using testing_support::slurp;

class ImportCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / fmt::format("odotune-cli-import-{}", ::getpid());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  // Runs odotune with `args` (already shell-quoted where needed).
  ProcResult odotune(const std::string& args) const {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string cmd = fmt::format("'{}' {} >'{}' 2>'{}'", ODOTUNE_BINARY, args, out.string(),
                                        err.string());
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
  }
  static std::string q(const fs::path& p) { return fmt::format("'{}'", p.string()); }
  fs::path dir_;
};

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }
std::size_t count_lines(const std::string& s) {
  std::size_t n = 0;
  for (char c : s) n += c == '\n' ? 1u : 0u;
  return n;
}

TEST_F(ImportCli, OptiOdomRunWritesTrackAndSummary) {
  const fs::path track = dir_ / "run01.csv";
  const auto r = odotune(fmt::format("import optiodom {} -o {}",
                                     q(kReal / "optiodom_diff/circular/231220200146/231220200146_run-01.csv"),
                                     q(track)));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(count_lines(r.out), 1u) << r.out;
  // SOURCE.md: 2066 samples, 103.25 s.
  EXPECT_TRUE(contains(r.out, "2066 rows")) << r.out;
  EXPECT_TRUE(contains(r.out, "103.250 s")) << r.out;
  EXPECT_TRUE(contains(r.out, "ticks_l")) << r.out;
  const tracks::Track tr = tracks::read_track(track);
  EXPECT_EQ(tr.size(), 2066u);
  EXPECT_TRUE(tr.has_ticks());
  EXPECT_TRUE(tr.has_cmd());
  EXPECT_TRUE(tr.meta().get("citation").has_value());
}

TEST_F(ImportCli, MrclamAndLitw) {
  const fs::path m = dir_ / "m1.csv";
  auto r = odotune(fmt::format("import mrclam {} --robot 1 -o {}", q(kReal / "mrclam7"), q(m)));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const tracks::Track tm = tracks::read_track(m);
  EXPECT_TRUE(contains(r.out, fmt::format("{} rows", tm.size()))) << r.out;
  EXPECT_TRUE(contains(r.out, "v_cmd")) << r.out;
  EXPECT_EQ(tm.meta().get("source.t0_unix"), "1248446182.116");

  const fs::path l = dir_ / "litw.csv";
  r = odotune(fmt::format("import litw {} -o {}", q(kReal / "utias_lost_in_the_woods/derived/litw_series.csv"),
                          q(l)));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // SOURCE.md: 12 609 samples over 1260.8 s.
  EXPECT_TRUE(contains(r.out, "12609 rows")) << r.out;
  EXPECT_TRUE(contains(r.out, "1260.800 s")) << r.out;
  EXPECT_EQ(tracks::read_track(l).size(), 12609u);
}

TEST_F(ImportCli, MissingInputIsOneLineAndNoOutput) {
  const fs::path track = dir_ / "never.csv";
  const fs::path missing = dir_ / "nothing_run-01.csv";
  auto r = odotune(fmt::format("import optiodom {} -o {}", q(missing), q(track)));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_TRUE(contains(r.err, missing.string())) << r.err;
  EXPECT_FALSE(fs::exists(track));

  r = odotune(fmt::format("import mrclam {} --robot 1 -o {}", q(dir_ / "no-folder"), q(track)));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.err, "no-folder")) << r.err;
  EXPECT_FALSE(fs::exists(track));

  r = odotune(fmt::format("import litw {}",
                          q(kReal / "utias_lost_in_the_woods/derived/litw_series.csv")));  // no -o
  EXPECT_NE(r.exit_code, 0);
}

TEST_F(ImportCli, HelpHasAnExample) {
  for (const char* sub : {"mrclam", "optiodom", "litw"}) {
    const auto r = odotune(fmt::format("import {} --help", sub));
    EXPECT_EQ(r.exit_code, 0) << sub;
    EXPECT_TRUE(contains(r.out, "Example")) << sub << ": " << r.out;
    EXPECT_TRUE(contains(r.out, "-o,--output")) << sub;
  }
}

TEST_F(ImportCli, RosbagListsImportsAndRefusesInOneLine) {
  const fs::path bags = kReal / "robot_localization_bags";
  auto r = odotune(fmt::format("import rosbag {} --list", q(bags / "ros2" / "test1_db3")));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "/husky_velocity_controller/odom")) << r.out;
  EXPECT_TRUE(contains(r.out, "sensor_msgs/NavSatFix")) << r.out;
  EXPECT_TRUE(contains(r.out, "11865")) << r.out;

  const fs::path track = dir_ / "husky.csv";
  r = odotune(fmt::format("import rosbag {} --imu-rpy 1.5707963267948966,0,-1.5707963267948966 -o {}",
                          q(bags / "ros2" / "test1.mcap"), q(track)));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "16806 rows")) << r.out;
  EXPECT_TRUE(contains(r.out, "fixes: /fix")) << r.out;
  const tracks::Track tr = tracks::read_track(track);
  EXPECT_TRUE(tr.has(tracks::Col::aps_var_x));
  EXPECT_NE(tr.meta().get("source.gyro")->find("roll 1.5708"), std::string::npos);

  // A wrong topic: one line, non-zero, nothing written.
  const fs::path never = dir_ / "never.csv";
  r = odotune(fmt::format("import rosbag {} --fix-topic /imu/data -o {}", q(bags / "ros2" / "test1.mcap"),
                          q(never)));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_TRUE(contains(r.err, "--fix-topic /imu/data is a sensor_msgs/Imu topic")) << r.err;
  EXPECT_FALSE(fs::exists(never));
  // Not a bag.
  r = odotune(fmt::format("import rosbag {} -o {}", q(track), q(never)));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.err, "not a bag")) << r.err;
  EXPECT_FALSE(fs::exists(never));
  // A ROS 1 bag cut short or with a damaged (bz2) chunk: one line naming it, nothing written.
  {
    std::ifstream in(bags / "test1.bag", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir_ / "cut.bag", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    for (std::size_t k = 0; k < 16; ++k) bytes[bytes.size() / 3 + 997 * k] ^= '\xff';
    std::ofstream(dir_ / "flipped.bag", std::ios::binary) << bytes;
  }
  for (const char* bad : {"cut.bag", "flipped.bag"}) {
    r = odotune(fmt::format("import rosbag {} -o {}", q(dir_ / bad), q(never)));
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    EXPECT_TRUE(contains(r.err, bad)) << r.err;
    EXPECT_FALSE(fs::exists(never));
  }
  // The help says whether ROS 1 bags are supported.
  r = odotune("import rosbag --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(contains(r.out, "ROS 1 .bag (")) << r.out;
  EXPECT_TRUE(contains(r.out, "Examples")) << r.out;
}

}  // namespace
}  // namespace odotune::cli

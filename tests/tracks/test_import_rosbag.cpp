// import_rosbag (odotune/tracks/import_rosbag.h): robot_localization's Husky
// recording imported from its ROS 1, MCAP and SQLite forms gives one track;
// the IMU mounting rotation makes the gyro agree with the odometry; the fixes'
// local frame; and, on small bags made here, JointState wheels, the stamp
// rules (backwards, repeated, zero), /tf_static and every refusal.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include <odotune/bags/bag.h>
#include <odotune/tracks/import_rosbag.h>
#include <odotune/tracks/track_io.h>

#include "support/ros2_bag.h"
#include "support/temp_dir.h"

namespace odotune::tracks {
namespace {

namespace fs = std::filesystem;
using testing_support::BagMessageSpec;
using testing_support::BagTopicSpec;

const fs::path kBags = fs::path(ODOTUNE_SHARED_DIR) / "data" / "real" / "robot_localization_bags";
constexpr double kPi = std::numbers::pi;

// The Husky's IMU mounting, from robot_localization's ROS 1 test
// (test_ekf_localization_node_bag1.test: static_transform_publisher args
// "0 -0.3 0.52 -1.570796327 0 1.570796327", i.e. yaw −π/2, pitch 0, roll π/2).
RosbagImportOptions husky() {
  RosbagImportOptions o;
  o.imu_rpy_rad = std::array<double, 3>{kPi / 2, 0.0, -kPi / 2};
  return o;
}

// Correlation and slope of gyro_z against w_cmd (the gyro sample at or after
// each odometry sample).
std::pair<double, double> gyro_vs_odometry(const Track& tr) {
  std::vector<double> a, b;
  const auto& w = tr.col(Col::w_cmd);
  const auto& g = tr.col(Col::gyro_z);
  double last_g = std::nan("");
  for (std::size_t i = tr.size(); i-- > 0;) {
    if (!std::isnan(g[i])) last_g = g[i];
    if (!std::isnan(w[i]) && !std::isnan(last_g)) {
      a.push_back(w[i]);
      b.push_back(last_g);
    }
  }
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i] / n;
    mb += b[i] / n;
  }
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return {sab / std::sqrt(saa * sbb), sab / saa};
}

TEST(ImportRosbag, HuskyGivesOneTrackFromItsThreeForms) {
  std::vector<fs::path> forms = {kBags / "ros2" / "test1.mcap", kBags / "ros2" / "test1_db3"};
  if (bags::ros1_supported()) forms.insert(forms.begin(), kBags / "test1.bag");
  const Track ref = import_rosbag(forms[0], husky());
  EXPECT_EQ(ref.size(), 16806u);  // every message has its own stamp
  EXPECT_NEAR(ref.duration_s(), 395.34, 0.01);
  for (Col c : {Col::v_cmd, Col::w_cmd, Col::gyro_z, Col::aps_x, Col::aps_y, Col::aps_var_x, Col::aps_var_y})
    EXPECT_TRUE(ref.has(c)) << column_name(c);
  for (std::size_t k = 1; k < forms.size(); ++k) {
    SCOPED_TRACE(forms[k].string());
    const Track tr = import_rosbag(forms[k], husky());
    ASSERT_EQ(tr.t(), ref.t());
    for (int c = 0; c < kNumCols; ++c) {
      const auto& x = tr.col(static_cast<Col>(c));
      const auto& y = ref.col(static_cast<Col>(c));
      ASSERT_EQ(x.size(), y.size()) << column_name(static_cast<Col>(c));
      for (std::size_t i = 0; i < x.size(); ++i)
        ASSERT_TRUE(x[i] == y[i] || (std::isnan(x[i]) && std::isnan(y[i])))
            << column_name(static_cast<Col>(c)) << " row " << i;
    }
    EXPECT_EQ(tr.meta().get("source.t0_ns"), ref.meta().get("source.t0_ns"));
  }
}

TEST(ImportRosbag, JackalGivesOneTrackFromItsThreeForms) {
  // test2: odometry and IMU only, in simulated time (no fixes).
  std::vector<fs::path> forms = {kBags / "ros2" / "test2.mcap", kBags / "ros2" / "test2_db3"};
  if (bags::ros1_supported()) forms.insert(forms.begin(), kBags / "test2.bag");
  const Track ref = import_rosbag(forms[0], {});
  EXPECT_EQ(ref.size(), 6121u);
  EXPECT_FALSE(ref.has(Col::aps_x));
  EXPECT_EQ(*ref.meta().get("source.fixes"), "none");
  for (std::size_t k = 1; k < forms.size(); ++k) {
    const Track tr = import_rosbag(forms[k], {});
    ASSERT_EQ(tr.t(), ref.t()) << forms[k];
    for (Col c : {Col::v_cmd, Col::w_cmd, Col::gyro_z})
      for (std::size_t i = 0; i < tr.size(); ++i)
        ASSERT_TRUE(tr.col(c)[i] == ref.col(c)[i] || (std::isnan(tr.col(c)[i]) && std::isnan(ref.col(c)[i])))
            << forms[k] << " " << column_name(c) << " row " << i;
  }
}

TEST(ImportRosbag, TheImuMountingMakesTheGyroAgreeWithTheOdometry) {
  const fs::path bag = kBags / "ros2" / "test1.mcap";
  const auto [corr, slope] = gyro_vs_odometry(import_rosbag(bag, husky()));
  EXPECT_GT(corr, 0.8);
  EXPECT_NEAR(slope, 1.0, 0.1);
  // Without it the IMU's z axis (horizontal on this robot) says nothing of the yaw.
  const auto [corr0, slope0] = gyro_vs_odometry(import_rosbag(bag, {}));
  EXPECT_LT(std::abs(corr0), 0.1);
  // The ROS 2 port's transcription (roll −π/2, yaw π/2) flips the sign.
  RosbagImportOptions swapped;
  swapped.imu_rpy_rad = std::array<double, 3>{-kPi / 2, 0.0, kPi / 2};
  EXPECT_LT(gyro_vs_odometry(import_rosbag(bag, swapped)).first, -0.8);
}

TEST(ImportRosbag, HuskyFixesInALocalEastNorthFrame) {
  const Track tr = import_rosbag(kBags / "ros2" / "test1.mcap", husky());
  const auto& x = tr.col(Col::aps_x);
  const auto& y = tr.col(Col::aps_y);
  std::size_t first = 0;
  while (std::isnan(x[first])) ++first;
  EXPECT_EQ(x[first], 0.0);
  EXPECT_EQ(y[first], 0.0);
  // The run's extent is that of a ~400 s outdoor drive at walking speed
  // (robot_localization's expected end point is about 86 m from the start).
  double max_r = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < tr.size(); ++i)
    if (!std::isnan(x[i])) {
      max_r = std::max(max_r, std::hypot(x[i], y[i]));
      ++n;
      EXPECT_GT(tr.col(Col::aps_var_x)[i], 0.0);
    }
  EXPECT_EQ(n, 989u);
  EXPECT_GT(max_r, 40.0);
  EXPECT_LT(max_r, 300.0);
  EXPECT_NE(tr.meta().get("source.fixes")->find("lat 42.375812000"), std::string::npos);
}

// --- small bags made here ---------------------------------------------------

constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;  // ns
std::int64_t at(double s) { return kT0 + static_cast<std::int64_t>(std::llround(s * 1e9)); }

TEST(ImportRosbag, JointStateWheelsFromVelocitiesOrPositions) {
  testing_support::TempDir dir;
  const fs::path bag = dir.path() / "wheels.mcap";
  const std::vector<std::string> names = {"front_left", "left_wheel", "right_wheel"};
  std::vector<BagMessageSpec> msgs;
  for (int k = 0; k < 5; ++k) {
    const double t = 0.1 * k;
    msgs.push_back(
        {0, static_cast<std::uint64_t>(at(t)),
         testing_support::joint_state(at(t), names, {0.0, 2.0 * t, 3.0 * t}, {})});  // positions only
  }
  testing_support::write_ros2_mcap(bag, {{"/joint_states", "sensor_msgs/msg/JointState"}}, msgs);
  RosbagImportOptions o;
  o.left_joint = "left_wheel";
  o.right_joint = "right_wheel";
  EXPECT_THROW(import_rosbag(bag, o), TrackError);  // no geometry
  o.wheel_radius_m = 0.1;
  o.wheel_base_m = 0.5;
  const Track tr = import_rosbag(bag, o);
  ASSERT_EQ(tr.size(), 4u);  // the first position only starts the differences
  for (std::size_t i = 0; i < tr.size(); ++i) {
    EXPECT_NEAR(tr.col(Col::omega_l)[i], 2.0, 1e-9);
    EXPECT_NEAR(tr.col(Col::omega_r)[i], 3.0, 1e-9);
  }
  EXPECT_EQ(tr.meta().wheel_base_m, 0.5);
  EXPECT_NE(tr.meta().get("source.odometry")->find("positions differenced"), std::string::npos);
}

TEST(ImportRosbag, StampsBackwardsRepeatedOrZero) {
  testing_support::TempDir dir;
  const fs::path bag = dir.path() / "stamps.mcap";
  std::vector<BagMessageSpec> msgs = {
      {0, static_cast<std::uint64_t>(at(0.0)), testing_support::odometry(at(0.0), 1.0, 0.0)},
      {0, static_cast<std::uint64_t>(at(0.2)), testing_support::odometry(at(0.2), 3.0, 0.0)},
      {0, static_cast<std::uint64_t>(at(0.21)), testing_support::odometry(at(0.1), 2.0, 0.0)},  // backwards
      {0, static_cast<std::uint64_t>(at(0.22)), testing_support::odometry(at(0.2), 9.0, 0.0)},  // repeated
  };
  testing_support::write_ros2_mcap(bag, {{"/odom", "nav_msgs/msg/Odometry"}}, msgs);
  const Track tr = import_rosbag(bag, {});
  ASSERT_EQ(tr.size(), 3u);
  EXPECT_EQ(tr.col(Col::v_cmd), (std::vector<double>{1.0, 2.0, 3.0}));
  const std::string note = *tr.meta().get("source.odometry");
  EXPECT_NE(note.find("1 stamps went backwards"), std::string::npos) << note;
  EXPECT_NE(note.find("1 repeated stamps"), std::string::npos) << note;
  // Receive times instead: four distinct times, in bag order.
  RosbagImportOptions rt;
  rt.receive_time_stamps = true;
  EXPECT_EQ(import_rosbag(bag, rt).col(Col::v_cmd), (std::vector<double>{1.0, 3.0, 2.0, 9.0}));

  const fs::path zero = dir.path() / "zero.mcap";
  testing_support::write_ros2_mcap(
      zero, {{"/odom", "nav_msgs/msg/Odometry"}},
      {{0, static_cast<std::uint64_t>(at(0.0)), testing_support::odometry(0, 1.0, 0.0)},
       {0, static_cast<std::uint64_t>(at(0.1)), testing_support::odometry(0, 1.0, 0.0)}});
  try {
    import_rosbag(zero, {});
    ADD_FAILURE() << "imported a topic without stamps";
  } catch (const TrackError& e) {
    EXPECT_NE(std::string(e.what()).find("--stamps receive"), std::string::npos) << e.what();
  }
  EXPECT_EQ(import_rosbag(zero, rt).size(), 2u);
}

TEST(ImportRosbag, ImuMountingFromTfStatic) {
  testing_support::TempDir dir;
  const fs::path bag = dir.path() / "tf.mcap";
  // imu_link rotated by roll π/2 about base_link's x: the IMU's y axis is up.
  const double s = std::sin(kPi / 4), c = std::cos(kPi / 4);
  testing_support::write_ros2_mcap(
      bag,
      {{"/odom", "nav_msgs/msg/Odometry"},
       {"/imu", "sensor_msgs/msg/Imu"},
       {"/tf_static", "tf2_msgs/msg/TFMessage"}},
      {{2, static_cast<std::uint64_t>(at(0.0)),
        testing_support::tf_message("base_link", "imu_link", s, 0, 0, c)},
       {0, static_cast<std::uint64_t>(at(0.0)), testing_support::odometry(at(0.0), 1.0, 0.3)},
       {1, static_cast<std::uint64_t>(at(0.05)), testing_support::imu(at(0.05), "imu_link", 0.0, 0.3, 0.0)}});
  const Track tr = import_rosbag(bag, {});
  EXPECT_NEAR(tr.col(Col::gyro_z)[1], 0.3, 1e-12);
  EXPECT_NE(tr.meta().get("source.gyro")->find("from /tf_static"), std::string::npos);
}

TEST(ImportRosbag, RefusalsNameTheProblem) {
  testing_support::TempDir dir;
  const fs::path bag = dir.path() / "two.mcap";
  testing_support::write_ros2_mcap(
      bag,
      {{"/odom", "nav_msgs/msg/Odometry"},
       {"/imu_a", "sensor_msgs/msg/Imu"},
       {"/imu_b", "sensor_msgs/msg/Imu"},
       {"/odometry/filtered", "nav_msgs/msg/Odometry"},
       {"/fix", "sensor_msgs/msg/NavSatFix"}},
      {{0, static_cast<std::uint64_t>(at(0.0)), testing_support::odometry(at(0.0), 1.0, 0.0)},
       {1, static_cast<std::uint64_t>(at(0.01)), testing_support::imu(at(0.01), "a", 0, 0, 0)},
       {2, static_cast<std::uint64_t>(at(0.02)), testing_support::imu(at(0.02), "b", 0, 0, 0)},
       {3, static_cast<std::uint64_t>(at(0.03)), testing_support::odometry(at(0.03), 1.0, 0.0)},
       {4, static_cast<std::uint64_t>(at(0.04)), testing_support::navsatfix(at(0.04), 0, 0, 1, -1)}});
  auto expect_error = [&](const RosbagImportOptions& o, const std::string& part) {
    try {
      import_rosbag(bag, o);
      ADD_FAILURE() << "no error; expected: " << part;
    } catch (const TrackError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(bag.string()), std::string::npos) << e.what();
    }
  };
  expect_error(
      {},
      "several IMU topics: /imu_a (sensor_msgs/Imu, 1), /imu_b (sensor_msgs/Imu, 1); choose one with --imu-topic");
  RosbagImportOptions o;
  o.imu_topic = "/imu_c";
  expect_error(o, "--imu-topic /imu_c: no such topic");
  o.imu_topic = "/odom";
  expect_error(o, "--imu-topic /odom is a nav_msgs/Odometry topic (expected sensor_msgs/Imu)");
  o.imu_topic = "none";
  o.gt_topic = "/odom";
  expect_error(o, "not ground truth");
  o.gt_topic.clear();
  // The filter's output is not taken for the odometry; the one fix had no fix
  // (status −1), so the fix column is absent.
  const Track tr = import_rosbag(bag, o);
  EXPECT_NE(tr.meta().get("source.odometry")->find("/odom (nav_msgs/Odometry, 1 samples)"), std::string::npos);
  EXPECT_FALSE(tr.has(Col::aps_x));
  EXPECT_NE(tr.meta().get("source.fixes")->find("1 messages dropped"), std::string::npos);
  EXPECT_THROW(import_rosbag(dir.path() / "missing.mcap", o), std::runtime_error);
}

}  // namespace
}  // namespace odotune::tracks

// Bags (odotune/bags/bag.h) on robot_localization's own recordings
// (../shared/data/real/robot_localization_bags, SOURCE.md there): each bag
// as a ROS 1 bag, an MCAP file and a rosbag2 SQLite folder written by
// independent tools must list the same topics and counts and decode, message
// by message, to the same values; plus the decoders on hand-made messages of
// both encodings and on cut or inflated messages.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <odotune/bags/bag.h>
#include <odotune/bags/bag_error.h>
#include <odotune/bags/ros_messages.h>

#include "support/ros2_bag.h"

namespace odotune::bags {
namespace {

namespace fs = std::filesystem;
const fs::path kBags = fs::path(ODOTUNE_SHARED_DIR) / "data" / "real" / "robot_localization_bags";

std::vector<fs::path> forms(const std::string& test) {
  std::vector<fs::path> f;
  if (ros1_supported()) f.push_back(kBags / (test + ".bag"));
  f.push_back(kBags / "ros2" / (test + ".mcap"));
  f.push_back(kBags / "ros2" / (test + "_db3"));
  return f;
}

TEST(Bags, Test1TopicsAndCountsAgreeAcrossTheThreeForms) {
  ASSERT_TRUE(fs::exists(kBags / "test1.bag"));
  for (const fs::path& p : forms("test1")) {
    SCOPED_TRACE(p.string());
    const BagInfo info = inspect_bag(p);
    std::map<std::string, std::pair<std::string, unsigned long long>> t;
    for (const auto& topic : info.topics) t[topic.name] = {topic.type, topic.count};
    EXPECT_EQ(t["/husky_velocity_controller/odom"], std::make_pair(std::string("nav_msgs/Odometry"), 3952ull));
    EXPECT_EQ(t["/imu/data"], std::make_pair(std::string("sensor_msgs/Imu"), 11865ull));
    EXPECT_EQ(t["/fix"], std::make_pair(std::string("sensor_msgs/NavSatFix"), 989ull));
    EXPECT_EQ(info.messages, 3952u + 11865u + 989u);
    EXPECT_NEAR(static_cast<double>(info.end_ns - info.start_ns) * 1e-9, 395.3, 0.05);
  }
}

// Every message of a topic, decoded, with its receive time.
template <class T>
std::vector<std::pair<std::int64_t, T>> all(const fs::path& bag, const std::string& topic,
                                            T (*decode)(std::span<const std::uint8_t>, WireEncoding)) {
  std::vector<std::pair<std::int64_t, T>> out;
  read_bag(
      bag, [&](std::string_view t) { return t == topic; },
      [&](const BagMessage& m) { out.emplace_back(m.receive_time_ns, decode(m.data, m.encoding)); });
  return out;
}

bool same(const ros::Header& a, const ros::Header& b) {
  return a.stamp_ns == b.stamp_ns && a.frame_id == b.frame_id;
}

TEST(Bags, Test1DecodesToTheSameValuesInEveryForm) {
  const auto f = forms("test1");
  const auto odom0 = all(f[0], "/husky_velocity_controller/odom", &ros::decode_odometry);
  const auto imu0 = all(f[0], "/imu/data", &ros::decode_imu);
  const auto fix0 = all(f[0], "/fix", &ros::decode_navsatfix);
  ASSERT_EQ(odom0.size(), 3952u);
  ASSERT_EQ(fix0.size(), 989u);
  // The first fix (SOURCE.md): 42.3758120 N, −71.1473947 E.
  EXPECT_NEAR(fix0[0].second.latitude_deg, 42.3758120, 5e-8);
  EXPECT_NEAR(fix0[0].second.longitude_deg, -71.1473947, 5e-8);
  for (std::size_t k = 1; k < f.size(); ++k) {
    SCOPED_TRACE(f[k].string());
    const auto odom = all(f[k], "/husky_velocity_controller/odom", &ros::decode_odometry);
    const auto imu = all(f[k], "/imu/data", &ros::decode_imu);
    const auto fix = all(f[k], "/fix", &ros::decode_navsatfix);
    ASSERT_EQ(odom.size(), odom0.size());
    ASSERT_EQ(imu.size(), imu0.size());
    ASSERT_EQ(fix.size(), fix0.size());
    for (std::size_t i = 0; i < odom.size(); ++i) {
      const auto& a = odom[i].second;
      const auto& b = odom0[i].second;
      // Receive times agree to 1 µs, not exactly: the converter of the ROS 2
      // forms (convert/convert.js) carried them as JavaScript doubles, which
      // round 1.4e18 ns to a multiple of 256 ns. The headers' stamps are exact.
      ASSERT_LE(std::abs(odom[i].first - odom0[i].first), 1000) << "odometry " << i;
      ASSERT_TRUE(same(a.header, b.header)) << "odometry " << i;
      ASSERT_EQ(a.child_frame_id, b.child_frame_id);
      ASSERT_EQ(a.linear.x, b.linear.x) << "odometry " << i;
      ASSERT_EQ(a.angular.z, b.angular.z) << "odometry " << i;
      ASSERT_EQ(a.position.x, b.position.x);
      ASSERT_EQ(a.orientation.w, b.orientation.w);
      ASSERT_EQ(a.twist_covariance, b.twist_covariance);
      ASSERT_EQ(a.pose_covariance, b.pose_covariance);
    }
    for (std::size_t i = 0; i < imu.size(); ++i) {
      const auto& a = imu[i].second;
      const auto& b = imu0[i].second;
      ASSERT_TRUE(same(a.header, b.header)) << "imu " << i;
      ASSERT_EQ(a.angular_velocity.z, b.angular_velocity.z) << "imu " << i;
      ASSERT_EQ(a.angular_velocity.x, b.angular_velocity.x) << "imu " << i;
      ASSERT_EQ(a.orientation.z, b.orientation.z);
      ASSERT_EQ(a.linear_acceleration.y, b.linear_acceleration.y);
      ASSERT_EQ(a.angular_velocity_covariance, b.angular_velocity_covariance);
    }
    for (std::size_t i = 0; i < fix.size(); ++i) {
      const auto& a = fix[i].second;
      const auto& b = fix0[i].second;
      ASSERT_TRUE(same(a.header, b.header)) << "fix " << i;
      ASSERT_EQ(a.status, b.status);
      ASSERT_EQ(a.latitude_deg, b.latitude_deg);
      ASSERT_EQ(a.longitude_deg, b.longitude_deg);
      ASSERT_EQ(a.altitude_m, b.altitude_m);
      ASSERT_EQ(a.position_covariance, b.position_covariance);
      ASSERT_EQ(a.covariance_type, b.covariance_type);
    }
  }
}

TEST(Bags, Test2IsTheJackalInSimulatedTime) {
  for (const fs::path& p : forms("test2")) {
    SCOPED_TRACE(p.string());
    const BagInfo info = inspect_bag(p);
    ASSERT_EQ(info.topics.size(), 2u);
    EXPECT_NEAR(static_cast<double>(info.start_ns) * 1e-9, 47.58,
                0.01);  // SOURCE.md: simulated time from 47.58 s
    const auto odom = all(p, "/jackal_velocity_controller/odom", &ros::decode_odometry);
    EXPECT_EQ(odom.size(), 3060u);
  }
}

using testing_support::Cdr;  // CDR for hand-made messages (support/ros2_bag.h)

TEST(Bags, CdrJointStateWithAlignmentAndBigEndian) {
  Cdr c;
  c.put(std::int32_t{12});
  c.put(std::uint32_t{345});
  c.str("base");  // frame_id: 4 + 5 bytes, then padding to 4
  c.put(std::uint32_t{2});
  c.str("left_wheel");
  c.str("right_wheel");
  c.put(std::uint32_t{2});
  c.put(1.5);  // aligned to 8 from the data start
  c.put(-2.25);
  c.put(std::uint32_t{0});
  c.put(std::uint32_t{0});
  const ros::JointState j = ros::decode_joint_state(c.b, WireEncoding::cdr);
  EXPECT_EQ(j.header.stamp_ns, 12'000'000'345);
  EXPECT_EQ(j.header.frame_id, "base");
  ASSERT_EQ(j.name.size(), 2u);
  EXPECT_EQ(j.name[1], "right_wheel");
  ASSERT_EQ(j.position.size(), 2u);
  EXPECT_EQ(j.position[0], 1.5);
  EXPECT_EQ(j.position[1], -2.25);
  EXPECT_TRUE(j.velocity.empty());

  // The same numbers big-endian (encapsulation 00 00).
  std::vector<std::uint8_t> be = {0, 0, 0, 0};
  auto put_be = [&](const void* p, std::size_t n) {
    while ((be.size() - 4) % n) be.push_back(0);
    const auto* q = static_cast<const std::uint8_t*>(p);
    for (std::size_t i = n; i-- > 0;) be.push_back(q[i]);
  };
  const std::int32_t sec = 12;
  const std::uint32_t nsec = 345, len = 1, zero = 0;
  put_be(&sec, 4);
  put_be(&nsec, 4);
  put_be(&len, 4);
  be.push_back(0);  // frame_id ""
  for (int k = 0; k < 4; ++k) put_be(&zero, 4);
  const ros::JointState jb = ros::decode_joint_state(be, WireEncoding::cdr);
  EXPECT_EQ(jb.header.stamp_ns, 12'000'000'345);
  EXPECT_TRUE(jb.name.empty());
}

TEST(Bags, CutOrInflatedMessagesThrowAndNeverCrash) {
  Cdr c;
  c.put(std::int32_t{1});
  c.put(std::uint32_t{0});
  c.str("map");
  c.put(std::uint32_t{1});
  c.str("wheel");
  c.put(std::uint32_t{1});
  c.put(0.5);
  c.put(std::uint32_t{0});
  c.put(std::uint32_t{0});
  ASSERT_NO_THROW(ros::decode_joint_state(c.b, WireEncoding::cdr));
  for (std::size_t cut = 0; cut < c.b.size(); ++cut) {
    const std::vector<std::uint8_t> part(c.b.begin(), c.b.begin() + static_cast<std::ptrdiff_t>(cut));
    EXPECT_ANY_THROW(ros::decode_joint_state(part, WireEncoding::cdr)) << "cut at " << cut;
  }
  // A count of 2^31 elements in a short message is refused before any allocation.
  auto big = c.b;
  const std::uint32_t huge = 0x80000000u;
  std::memcpy(big.data() + 16, &huge, 4);  // the name count
  EXPECT_ANY_THROW(ros::decode_joint_state(big, WireEncoding::cdr));
  // Random bytes: an exception or a value, never a crash.
  std::uint64_t s = 3;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<std::uint8_t> junk(4 + trial % 300);
    for (auto& x : junk) {
      s = s * 6364136223846793005ULL + 1442695040888963407ULL;
      x = static_cast<std::uint8_t>(s >> 56);
    }
    junk[0] = 0;
    junk[1] = 1;
    for (auto decode :
         {+[](std::span<const std::uint8_t> d) { (void)ros::decode_odometry(d, WireEncoding::cdr); },
          +[](std::span<const std::uint8_t> d) { (void)ros::decode_tf_message(d, WireEncoding::cdr); },
          +[](std::span<const std::uint8_t> d) { (void)ros::decode_joint_state(d, WireEncoding::ros1); }}) {
      try {
        decode(junk);
      } catch (const std::exception&) {
      }
    }
  }
  SUCCEED();
}

TEST(Bags, NotABagNamesTheFile) {
  const fs::path tmp = fs::temp_directory_path() / "odotune_not_a_bag.bag";
  {
    std::ofstream out(tmp);
    out << "hello\n";
  }
  try {
    inspect_bag(tmp);
    ADD_FAILURE() << "read a text file as a bag";
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find("not a bag"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(tmp.string()), std::string::npos) << e.what();
  }
  fs::remove(tmp);
  EXPECT_THROW(inspect_bag(fs::temp_directory_path() / "odotune_no_such_bag"), BagError);
}

}  // namespace
}  // namespace odotune::bags

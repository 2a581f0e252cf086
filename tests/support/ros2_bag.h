// Test support (header-only): small ROS 2 bags (MCAP, CDR messages) made in a
// test, for the importer's rules that the shared recordings do not exercise
// (JointState wheels, repeated and backward stamps, zero stamps, several
// candidate topics, /tf_static).
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/mcap_writer.h"

namespace odotune::testing_support {

// CDR (little-endian, XCDR1), alignment counted from the byte after the
// 4-byte encapsulation header.
struct Cdr {
  std::vector<std::uint8_t> b = {0, 1, 0, 0};
  void align(std::size_t n) {
    while ((b.size() - 4) % n) b.push_back(0);
  }
  template <class T>
  Cdr& put(T v) {
    align(sizeof(T));
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    b.insert(b.end(), p, p + sizeof(T));
    return *this;
  }
  Cdr& str(const std::string& s) {
    put(static_cast<std::uint32_t>(s.size() + 1));
    b.insert(b.end(), s.begin(), s.end());
    b.push_back(0);
    return *this;
  }
  Cdr& header(std::int64_t stamp_ns, const std::string& frame) {
    put(static_cast<std::int32_t>(stamp_ns / 1000000000));
    put(static_cast<std::uint32_t>(stamp_ns % 1000000000));
    return str(frame);
  }
  Cdr& doubles(std::size_t n, double v = 0.0) {
    for (std::size_t i = 0; i < n; ++i) put(v);
    return *this;
  }
};

inline std::vector<std::uint8_t> odometry(std::int64_t stamp_ns, double v, double w, double x = 0.0,
                                          double y = 0.0) {
  Cdr c;
  c.header(stamp_ns, "odom").str("base_link");
  c.put(x).put(y).put(0.0);               // position
  c.put(0.0).put(0.0).put(0.0).put(1.0);  // orientation
  c.doubles(36);                          // pose covariance
  c.put(v).put(0.0).put(0.0);             // linear
  c.put(0.0).put(0.0).put(w);             // angular
  c.doubles(36);                          // twist covariance
  return c.b;
}

inline std::vector<std::uint8_t> imu(std::int64_t stamp_ns, const std::string& frame, double wx, double wy,
                                     double wz) {
  Cdr c;
  c.header(stamp_ns, frame);
  c.put(0.0).put(0.0).put(0.0).put(1.0).doubles(9);
  c.put(wx).put(wy).put(wz).doubles(9);
  c.put(0.0).put(0.0).put(9.81).doubles(9);
  return c.b;
}

inline std::vector<std::uint8_t> navsatfix(std::int64_t stamp_ns, double lat, double lon, double var,
                                           std::int8_t status = 0) {
  Cdr c;
  c.header(stamp_ns, "gps");
  c.put(status).put(std::uint16_t{1});
  c.put(lat).put(lon).put(10.0);
  c.put(var).put(0.0).put(0.0).put(0.0).put(var).put(0.0).put(0.0).put(0.0).put(4.0 * var);
  c.put(std::uint8_t{2});
  return c.b;
}

inline std::vector<std::uint8_t> joint_state(std::int64_t stamp_ns, const std::vector<std::string>& names,
                                             const std::vector<double>& position,
                                             const std::vector<double>& velocity) {
  Cdr c;
  c.header(stamp_ns, "");
  c.put(static_cast<std::uint32_t>(names.size()));
  for (const auto& n : names) c.str(n);
  c.put(static_cast<std::uint32_t>(position.size()));
  for (double p : position) c.put(p);
  c.put(static_cast<std::uint32_t>(velocity.size()));
  for (double v : velocity) c.put(v);
  c.put(std::uint32_t{0});  // effort
  return c.b;
}

// tf2_msgs/TFMessage with one transform parent → child of rotation q (x, y, z, w).
inline std::vector<std::uint8_t> tf_message(const std::string& parent, const std::string& child, double qx,
                                            double qy, double qz, double qw) {
  Cdr c;
  c.put(std::uint32_t{1});
  c.header(0, parent).str(child);
  c.put(0.0).put(0.0).put(0.0);
  c.put(qx).put(qy).put(qz).put(qw);
  return c.b;
}

struct BagTopicSpec {
  std::string name, type;  // type as ROS 2 writes it: "nav_msgs/msg/Odometry"
};
struct BagMessageSpec {
  std::size_t topic = 0;  // index into the topics
  std::uint64_t log_time_ns = 0;
  std::vector<std::uint8_t> data;
};

// An MCAP ROS 2 bag (profile-less, unchunked, one schema per topic).
inline void write_ros2_mcap(const std::filesystem::path& path, const std::vector<BagTopicSpec>& topics,
                            const std::vector<BagMessageSpec>& messages) {
  using namespace bags::mcap;
  std::vector<Record> records;
  for (std::size_t i = 0; i < topics.size(); ++i) {
    const auto id = static_cast<std::uint16_t>(i + 1);
    records.push_back(Schema{id, topics[i].type, "ros2msg", {}});
    records.push_back(Channel{id, id, topics[i].name, "cdr", {}});
  }
  std::uint32_t seq = 0;
  for (const auto& m : messages)
    records.push_back(Message{static_cast<std::uint16_t>(m.topic + 1), seq++, m.log_time_ns, m.log_time_ns,
                              m.data});
  const auto bytes = bags::mcap::testing::conformance_file({}, records);
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace odotune::testing_support

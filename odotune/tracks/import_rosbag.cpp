#include <odotune/tracks/import_rosbag.h>

#include <Eigen/Geometry>
#include <GeographicLib/LocalCartesian.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include <odotune/bags/bag.h>
#include <odotune/bags/bag_error.h>
#include <odotune/bags/ros_messages.h>
#include <odotune/tracks/track_io.h>

namespace odotune::tracks {
namespace {

namespace fs = std::filesystem;
namespace ros = bags::ros;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kOdometry = "nav_msgs/Odometry";
constexpr const char* kJointState = "sensor_msgs/JointState";
constexpr const char* kImu = "sensor_msgs/Imu";
constexpr const char* kNavSatFix = "sensor_msgs/NavSatFix";
constexpr const char* kPose = "geometry_msgs/PoseStamped";
constexpr const char* kPoseCov = "geometry_msgs/PoseWithCovarianceStamped";
constexpr const char* kTf = "tf2_msgs/TFMessage";

[[noreturn]] void fail_import(const fs::path& bag, const std::string& reason) {
  throw TrackError(bag.string(), 0, reason);
}

std::string topic_list(const std::vector<bags::BagTopic>& topics) {
  std::string s;
  for (const auto& t : topics)
    s += fmt::format("{}{} ({}, {})", s.empty() ? "" : ", ", t.name, t.type, t.count);
  return s;
}

const bags::BagTopic* find_topic(const bags::BagInfo& info, const std::string& name) {
  for (const auto& t : info.topics)
    if (t.name == name) return &t;
  return nullptr;
}

// The topic for one role: the named one (checked to exist and have one of
// `types`), or the only topic of those types that `eligible` accepts; ""
// when none and the role is optional. Several candidates stop the import.
std::string choose(const fs::path& bag, const bags::BagInfo& info, const std::string& given, const char* role,
                   const char* flag, const std::vector<std::string>& types, bool required,
                   const std::function<bool(const bags::BagTopic&)>& eligible = nullptr) {
  auto typed = [&](const bags::BagTopic& t) {
    return std::find(types.begin(), types.end(), t.type) != types.end();
  };
  const std::string wanted = fmt::format("{}", fmt::join(types, " or "));
  if (given == "none") {
    if (required) fail_import(bag, fmt::format("{} cannot be none", flag));
    return "";
  }
  if (!given.empty()) {
    const bags::BagTopic* t = find_topic(info, given);
    if (!t)
      fail_import(bag, fmt::format("{} {}: no such topic in the bag (its topics: {})", flag, given,
                                   topic_list(info.topics)));
    if (!typed(*t))
      fail_import(bag, fmt::format("{} {} is a {} topic (expected {})", flag, given, t->type, wanted));
    return given;
  }
  std::vector<bags::BagTopic> candidates;
  for (const auto& t : info.topics)
    if (typed(t) && (!eligible || eligible(t))) candidates.push_back(t);
  if (candidates.size() == 1) return candidates.front().name;
  if (candidates.empty()) {
    if (required)
      fail_import(bag, fmt::format("no {} topic ({}) in the bag; its topics: {}", role, wanted,
                                   topic_list(info.topics)));
    return "";
  }
  fail_import(bag, fmt::format("several {} topics: {}; choose one with {} TOPIC", role, topic_list(candidates),
                               flag));
}

// One decoded sample on the track's clock.
struct Sample {
  std::int64_t stamp_ns = 0;
  std::array<double, 4> v{kNan, kNan, kNan, kNan};
};
struct Stream {
  std::string topic, type;
  std::vector<Sample> samples;
  std::size_t zero_stamps = 0, out_of_order = 0, duplicates = 0, dropped = 0;
};

// Sorts by stamp (stable), counting stamps that went backwards, and keeps
// the first of equal stamps, counting the rest.
void order(Stream& s) {
  for (std::size_t i = 1; i < s.samples.size(); ++i)
    s.out_of_order += s.samples[i].stamp_ns < s.samples[i - 1].stamp_ns;
  std::stable_sort(s.samples.begin(), s.samples.end(),
                   [](const Sample& a, const Sample& b) { return a.stamp_ns < b.stamp_ns; });
  std::vector<Sample> kept;
  kept.reserve(s.samples.size());
  for (const Sample& x : s.samples) {
    if (!kept.empty() && kept.back().stamp_ns == x.stamp_ns) {
      ++s.duplicates;
      continue;
    }
    kept.push_back(x);
  }
  s.samples = std::move(kept);
}

using Rotation = Eigen::Matrix3d;  // maps a child frame's vectors to its parent's

// R = Rz(yaw)·Ry(pitch)·Rx(roll): a frame given by fixed-axis roll, pitch,
// yaw (REP 103, tf's setRPY).
Rotation rotation_rpy(const std::array<double, 3>& rpy) {
  return (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}
Rotation rotation_quat(const ros::Quaternion& q) {
  return Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
}
double yaw_of(const ros::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

// The rotation from `child` to `parent` through /tf_static transforms
// (parent → … → child), if they connect.
std::optional<Rotation> static_rotation(const std::vector<ros::TransformStamped>& tf, const std::string& parent,
                                        const std::string& child) {
  auto strip = [](std::string f) { return !f.empty() && f[0] == '/' ? f.substr(1) : f; };
  std::string frame = strip(child);
  Rotation r = Rotation::Identity();
  for (std::size_t hop = 0; hop < tf.size() + 1; ++hop) {
    if (frame == strip(parent)) return r;
    const ros::TransformStamped* up = nullptr;
    for (const auto& t : tf)
      if (strip(t.child_frame_id) == frame) up = &t;
    if (!up) return std::nullopt;
    r = rotation_quat(up->rotation) * r;
    frame = strip(up->header.frame_id);
  }
  return std::nullopt;
}

// The topics of each role, chosen and checked against the options.
struct Topics {
  std::string odom, odom_type, imu, fix, gt, tf_topic;
  bool joints = false;  // odometry from a sensor_msgs/JointState topic
};

Topics choose_topics(const fs::path& bag, const bags::BagInfo& info, const RosbagImportOptions& o) {
  Topics tp;
  // Odometry: a robot_localization output (/odometry/filtered, …) is not the base's.
  auto base_odometry = [](const bags::BagTopic& t) {
    return t.name.find("filtered") == std::string::npos && t.name.find("ekf") == std::string::npos &&
           t.name.find("ukf") == std::string::npos;
  };
  tp.odom = choose(bag, info, o.odom_topic, "odometry", "--odom-topic", {kOdometry}, false, base_odometry);
  if (tp.odom.empty())
    tp.odom = choose(bag, info, o.odom_topic, "odometry", "--odom-topic", {kOdometry, kJointState}, true);
  tp.odom_type = find_topic(info, tp.odom)->type;
  tp.imu = choose(bag, info, o.imu_topic, "IMU", "--imu-topic", {kImu}, false);
  tp.fix = choose(bag, info, o.fix_topic, "position fix", "--fix-topic", {kNavSatFix, kPoseCov, kPose}, false);
  tp.gt = o.gt_topic.empty()
              ? std::string()
              : choose(bag, info, o.gt_topic, "ground truth", "--gt-topic", {kOdometry, kPoseCov, kPose}, true);
  if (!tp.gt.empty() && tp.gt == tp.odom)
    fail_import(bag, "--gt-topic is the odometry topic: a robot's own odometry is not ground truth");
  tp.joints = tp.odom_type == kJointState;
  if (tp.joints) {
    if (o.left_joint.empty() || o.right_joint.empty())
      fail_import(bag,
                  fmt::format("odometry from {} (sensor_msgs/JointState) needs --left-joint and --right-joint",
                              tp.odom));
    if (!o.wheel_radius_m || !o.wheel_base_m || !(*o.wheel_radius_m > 0) || !(*o.wheel_base_m > 0))
      fail_import(bag,
                  fmt::format("odometry from {} (sensor_msgs/JointState) needs --wheel-radius and --wheel-base "
                              "(> 0, in m)",
                              tp.odom));
  }
  if (o.imu_rpy_rad)
    for (double a : *o.imu_rpy_rad)
      if (!std::isfinite(a)) fail_import(bag, "--imu-rpy must be three finite angles in rad");
  tp.tf_topic = find_topic(info, "/tf_static") ? "/tf_static" : "";
  return tp;
}

// What reading the bag gathers: the streams and what the decoders learn on
// the way.
struct BagRead {
  std::map<std::string, Stream> streams;
  std::vector<ros::TransformStamped> tf_static;
  std::string imu_frame, base_frame;
  std::optional<ros::NavSatFix> origin_fix;
  std::optional<GeographicLib::LocalCartesian> local;  // the tangent frame at origin_fix
  std::map<std::string, std::size_t> message_counts;
  // JointState differencing state.
  std::optional<std::pair<std::int64_t, std::array<double, 2>>> last_joint_pos;
  bool joint_velocity_seen = false, joint_position_used = false;
};

void read_odometry_sample(const bags::BagMessage& m, BagRead& rd, Sample& x, std::int64_t& header_ns) {
  const ros::Odometry od = ros::decode_odometry(m.data, m.encoding);
  header_ns = od.header.stamp_ns;
  if (rd.base_frame.empty()) rd.base_frame = od.child_frame_id;
  x.v = {od.linear.x, od.angular.z, kNan, kNan};
}

// The two wheel joints' rates (their velocities, else their positions
// differenced); false when the message is dropped.
bool read_joint_sample(const bags::BagMessage& m, const RosbagImportOptions& o, BagRead& rd, Stream& s,
                       Sample& x, std::int64_t& header_ns) {
  const ros::JointState j = ros::decode_joint_state(m.data, m.encoding);
  header_ns = j.header.stamp_ns;
  const auto li = std::find(j.name.begin(), j.name.end(), o.left_joint);
  const auto ri = std::find(j.name.begin(), j.name.end(), o.right_joint);
  if (li == j.name.end() || ri == j.name.end()) {
    ++s.dropped;  // a JointState of other joints
    return false;
  }
  const auto a = static_cast<std::size_t>(li - j.name.begin());
  const auto b = static_cast<std::size_t>(ri - j.name.begin());
  const std::int64_t stamp = o.receive_time_stamps ? m.receive_time_ns : header_ns;
  auto& last_joint_pos = rd.last_joint_pos;
  if (j.velocity.size() == j.name.size()) {
    rd.joint_velocity_seen = true;
    x.v = {j.velocity[a], j.velocity[b], kNan, kNan};
  } else if (j.position.size() == j.name.size()) {
    rd.joint_position_used = true;
    const std::array<double, 2> pos{j.position[a], j.position[b]};
    if (!last_joint_pos || stamp <= last_joint_pos->first) {
      last_joint_pos = std::make_pair(stamp, pos);
      ++s.dropped;
      return false;
    }
    const double dt = static_cast<double>(stamp - last_joint_pos->first) * 1e-9;
    x.v = {(pos[0] - last_joint_pos->second[0]) / dt, (pos[1] - last_joint_pos->second[1]) / dt, kNan, kNan};
    last_joint_pos = std::make_pair(stamp, pos);
  } else {
    ++s.dropped;
    return false;
  }
  return true;
}

void read_imu_sample(const bags::BagMessage& m, BagRead& rd, Sample& x, std::int64_t& header_ns) {
  const ros::Imu im = ros::decode_imu(m.data, m.encoding);
  header_ns = im.header.stamp_ns;
  if (rd.imu_frame.empty()) rd.imu_frame = im.header.frame_id;
  x.v = {im.angular_velocity.x, im.angular_velocity.y, im.angular_velocity.z, kNan};
}

// A NavSatFix in local east, north [m] around the first fix; false when it
// holds no fix.
bool read_navsat_sample(const bags::BagMessage& m, BagRead& rd, Stream& s, Sample& x, std::int64_t& header_ns) {
  const ros::NavSatFix f = ros::decode_navsatfix(m.data, m.encoding);
  header_ns = f.header.stamp_ns;
  if (f.status < 0 || !std::isfinite(f.latitude_deg) || !std::isfinite(f.longitude_deg)) {
    ++s.dropped;  // no fix
    return false;
  }
  if (!rd.origin_fix) {
    rd.origin_fix = f;
    rd.local.emplace(f.latitude_deg, f.longitude_deg, std::isfinite(f.altitude_m) ? f.altitude_m : 0.0);
  }
  double e = 0, n = 0, u = 0;
  rd.local->Forward(f.latitude_deg, f.longitude_deg, std::isfinite(f.altitude_m) ? f.altitude_m : 0.0, e, n, u);
  const bool known = f.covariance_type != 0;
  x.v = {e, n, known ? f.position_covariance[0] : kNan, known ? f.position_covariance[4] : kNan};
  return true;
}

// Pose topics (fixes or ground truth) and, for ground truth, Odometry.
void read_pose_sample(const bags::BagMessage& m, const Stream& s, bool is_fix, Sample& x,
                      std::int64_t& header_ns) {
  ros::PoseStamped p;
  if (s.type == kPose) {
    p = ros::decode_pose_stamped(m.data, m.encoding);
  } else if (s.type == kPoseCov) {
    p = ros::decode_pose_with_covariance_stamped(m.data, m.encoding);
  } else {
    const ros::Odometry od = ros::decode_odometry(m.data, m.encoding);
    p.header = od.header;
    p.position = od.position;
    p.orientation = od.orientation;
  }
  header_ns = p.header.stamp_ns;
  if (is_fix)
    x.v = {p.position.x, p.position.y, p.covariance ? (*p.covariance)[0] : kNan,
           p.covariance ? (*p.covariance)[7] : kNan};
  else
    x.v = {p.position.x, p.position.y, yaw_of(p.orientation), kNan};
}

// One message of a chosen topic (or of /tf_static) into its stream; decoding
// errors name the message and its topic.
void read_message(const fs::path& bag, const Topics& tp, const RosbagImportOptions& o,
                  const bags::BagMessage& m, BagRead& rd) {
  const std::string topic(m.topic);
  const std::size_t k = ++rd.message_counts[topic];
  try {
    if (topic == tp.tf_topic && rd.streams.count(topic) == 0) {
      if (m.type == kTf)
        for (auto& tr : ros::decode_tf_message(m.data, m.encoding).transforms)
          rd.tf_static.push_back(std::move(tr));
      return;
    }
    Stream& s = rd.streams.at(topic);
    Sample x;
    std::int64_t header_ns = 0;
    if (topic == tp.odom && !tp.joints) {
      read_odometry_sample(m, rd, x, header_ns);
    } else if (topic == tp.odom) {
      if (!read_joint_sample(m, o, rd, s, x, header_ns)) return;
    } else if (topic == tp.imu) {
      read_imu_sample(m, rd, x, header_ns);
    } else if (topic == tp.fix && s.type == kNavSatFix) {
      if (!read_navsat_sample(m, rd, s, x, header_ns)) return;
    } else if (topic == tp.fix || topic == tp.gt) {
      read_pose_sample(m, s, topic == tp.fix, x, header_ns);
    }
    if (!o.receive_time_stamps && header_ns == 0) ++s.zero_stamps;
    x.stamp_ns = o.receive_time_stamps ? m.receive_time_ns : header_ns;
    s.samples.push_back(x);
  } catch (const bags::ByteReader::Short& e) {
    throw bags::BagError(bag.string(), fmt::format("message {} of {}", k, topic),
                         std::string("cut off: ") + e.what());
  } catch (const std::runtime_error& e) {
    if (dynamic_cast<const bags::BagError*>(&e)) throw;
    throw bags::BagError(bag.string(), fmt::format("message {} of {}", k, topic), e.what());
  }
}

// Reads the chosen topics' streams, each ordered by stamp, and checks them.
BagRead read_streams(const fs::path& bag, const bags::BagInfo& info, const Topics& tp,
                     const RosbagImportOptions& o) {
  BagRead rd;
  for (const std::string& t : {tp.odom, tp.imu, tp.fix, tp.gt})
    if (!t.empty()) rd.streams[t] = Stream{t, find_topic(info, t)->type, {}, 0, 0, 0, 0};
  bags::read_bag(
      bag,
      [&](std::string_view t) {
        return rd.streams.count(std::string(t)) > 0 || (!tp.tf_topic.empty() && t == tp.tf_topic);
      },
      [&](const bags::BagMessage& m) { read_message(bag, tp, o, m, rd); });

  for (auto& [topic, s] : rd.streams) {
    if (!s.samples.empty() && s.zero_stamps == s.samples.size())
      fail_import(
          bag,
          fmt::format("{}: every header stamp is zero (the driver does not stamp its messages); import with "
                      "--stamps receive",
                      topic));
    order(s);
  }
  if (rd.streams.at(tp.odom).samples.empty())
    fail_import(bag,
                fmt::format("{}: no usable odometry message{}", tp.odom,
                            tp.joints ? fmt::format(" (none names both {} and {})", o.left_joint, o.right_joint)
                                      : ""));
  return rd;
}

// The IMU's mounting in the base frame: given (--imu-rpy), from /tf_static,
// or none; with the note that says which.
std::pair<Rotation, std::string> imu_mounting(const RosbagImportOptions& o, const BagRead& rd) {
  Rotation imu_rot = Rotation::Identity();
  std::string imu_rot_note;
  const std::string& imu_frame = rd.imu_frame;
  const std::string& base_frame = rd.base_frame;
  if (o.imu_rpy_rad) {
    imu_rot = rotation_rpy(*o.imu_rpy_rad);
    imu_rot_note = fmt::format("roll {:.6g}, pitch {:.6g}, yaw {:.6g} rad relative to the base frame (given)",
                               (*o.imu_rpy_rad)[0], (*o.imu_rpy_rad)[1], (*o.imu_rpy_rad)[2]);
  } else if (const auto r = static_rotation(rd.tf_static, base_frame.empty() ? "base_link" : base_frame,
                                            imu_frame);
             r && !imu_frame.empty()) {
    imu_rot = *r;
    imu_rot_note = fmt::format("from /tf_static, {} → {}", base_frame.empty() ? "base_link" : base_frame,
                               imu_frame);
  } else {
    imu_rot_note = fmt::format(
        "none: the IMU frame '{}' is taken as the base frame (no --imu-rpy, no /tf_static "
        "path from '{}')",
        imu_frame, base_frame.empty() ? "base_link" : base_frame);
  }
  return {imu_rot, imu_rot_note};
}

// The rows: one per distinct stamp of any stream, each stream's samples in
// their columns; sets *t0_ns to the first stamp.
TrackData fill_rows(const Topics& tp, const BagRead& rd, const Rotation& imu_rot, std::int64_t* t0_ns) {
  const auto& streams = rd.streams;
  std::vector<std::int64_t> stamps;
  for (const auto& [topic, s] : streams)
    for (const Sample& x : s.samples) stamps.push_back(x.stamp_ns);
  std::sort(stamps.begin(), stamps.end());
  stamps.erase(std::unique(stamps.begin(), stamps.end()), stamps.end());
  const std::int64_t t0 = stamps.front();
  TrackData d;
  d.t.reserve(stamps.size());
  for (const std::int64_t s : stamps) d.t.push_back(static_cast<double>(s - t0) * 1e-9);
  auto row_of = [&](std::int64_t s) {
    return static_cast<std::size_t>(std::lower_bound(stamps.begin(), stamps.end(), s) - stamps.begin());
  };
  auto fill = [&](const std::string& topic, std::initializer_list<std::pair<Col, int>> cols,
                  const std::function<void(std::array<double, 4>&)>& transform = nullptr) {
    if (streams.at(topic).samples.empty()) return;  // e.g. no message had a fix
    for (const auto& [c, k] : cols) d.ensure(c);
    for (Sample x : streams.at(topic).samples) {
      if (transform) transform(x.v);
      const std::size_t r = row_of(x.stamp_ns);
      for (const auto& [c, k] : cols) d.col(c)[r] = x.v[static_cast<std::size_t>(k)];
    }
  };
  if (tp.joints)
    fill(tp.odom, {{Col::omega_l, 0}, {Col::omega_r, 1}});
  else
    fill(tp.odom, {{Col::v_cmd, 0}, {Col::w_cmd, 1}});
  if (!tp.imu.empty())
    fill(tp.imu, {{Col::gyro_z, 0}},
         [&](std::array<double, 4>& v) { v[0] = imu_rot.row(2).dot(Eigen::Vector3d(v[0], v[1], v[2])); });
  if (!tp.fix.empty()) {
    bool has_var = false;
    for (const Sample& x : streams.at(tp.fix).samples)
      has_var |= std::isfinite(x.v[2]) || std::isfinite(x.v[3]);
    if (has_var)
      fill(tp.fix, {{Col::aps_x, 0}, {Col::aps_y, 1}, {Col::aps_var_x, 2}, {Col::aps_var_y, 3}});
    else
      fill(tp.fix, {{Col::aps_x, 0}, {Col::aps_y, 1}});
  }
  if (!tp.gt.empty()) fill(tp.gt, {{Col::gt_x, 0}, {Col::gt_y, 1}, {Col::gt_theta, 2}});
  *t0_ns = t0;
  return d;
}

// The track's metadata: name, geometry, and where each column came from.
void add_rosbag_metadata(const fs::path& bag, const bags::BagInfo& info, const RosbagImportOptions& o,
                         const Topics& tp, const BagRead& rd, const std::string& imu_rot_note, std::int64_t t0,
                         TrackMeta& meta) {
  meta.name = bag.filename().string();
  meta.origin = "recorded";
  if (tp.joints) {
    meta.wheel_radius_left_m = meta.wheel_radius_right_m = *o.wheel_radius_m;
    meta.wheel_base_m = *o.wheel_base_m;
  } else {
    if (o.wheel_radius_m) meta.wheel_radius_left_m = meta.wheel_radius_right_m = *o.wheel_radius_m;
    if (o.wheel_base_m) meta.wheel_base_m = *o.wheel_base_m;
    meta.body_velocity = BodyVelocitySource::measured;  // an Odometry message's twist
  }
  auto& x = meta.extra;
  x.emplace_back("source",
                 fmt::format("ROS bag {} ({}, {} messages over {:.3f} s, read by odotune import rosbag)",
                             bag.string(), bags::to_string(info.format), info.messages,
                             static_cast<double>(info.end_ns - info.start_ns) * 1e-9));
  x.emplace_back("source.bag_topics", topic_list(info.topics));
  x.emplace_back("source.stamps", o.receive_time_stamps ? "receive times recorded by the bag (--stamps receive)"
                                                        : "message header stamps");
  x.emplace_back("source.t0_ns", std::to_string(t0));
  auto note = [&](const std::string& topic, const std::string& what) {
    const Stream& s = rd.streams.at(topic);
    std::string extra;
    if (s.out_of_order) extra += fmt::format("; {} stamps went backwards (sorted)", s.out_of_order);
    if (s.duplicates) extra += fmt::format("; {} repeated stamps (first kept)", s.duplicates);
    if (s.dropped) extra += fmt::format("; {} messages dropped", s.dropped);
    return fmt::format("{} ({}, {} samples): {}{}", topic, s.type, s.samples.size(), what, extra);
  };
  x.emplace_back(
      "source.odometry",
      note(tp.odom,
           tp.joints
               ? fmt::format("joints {} and {} → omega_l, omega_r ({}){}", o.left_joint, o.right_joint,
                             rd.joint_velocity_seen ? "their velocities" : "their positions differenced",
                             rd.joint_position_used && rd.joint_velocity_seen ? ", positions where no velocity"
                                                                              : "")
               : "twist.linear.x → v_cmd, twist.angular.z → w_cmd (base frame " +
                     (rd.base_frame.empty() ? std::string("?") : rd.base_frame) + ")"));
  if (!tp.imu.empty())
    x.emplace_back("source.gyro", note(tp.imu, "angular_velocity rotated into the base frame, its z → gyro_z; "
                                               "mounting " +
                                                   imu_rot_note));
  else
    x.emplace_back("source.gyro", "none (no sensor_msgs/Imu topic chosen)");
  if (!tp.fix.empty()) {
    if (rd.streams.at(tp.fix).type == kNavSatFix && rd.origin_fix)
      x.emplace_back("source.fixes",
                     note(tp.fix,
                          fmt::format("WGS84 → local east, north [m] around the first fix (lat {:.9f}, lon "
                                      "{:.9f}, alt {:.3f} m; GeographicLib LocalCartesian) → aps_x, aps_y; "
                                      "position_covariance[0], [4] → aps_var_x, aps_var_y unless its type "
                                      "is unknown; status −1 dropped",
                                      rd.origin_fix->latitude_deg, rd.origin_fix->longitude_deg,
                                      rd.origin_fix->altitude_m)));
    else
      x.emplace_back("source.fixes", note(tp.fix, "position.x, position.y → aps_x, aps_y (covariance[0], [7] → "
                                                  "aps_var_x, aps_var_y when given)"));
  } else {
    x.emplace_back("source.fixes", "none");
  }
  if (!tp.gt.empty())
    x.emplace_back("source.ground_truth",
                   note(tp.gt, "position.x, position.y, yaw of the orientation → gt_x, gt_y, gt_theta"));
}

}  // namespace

std::vector<std::string> describe_bag_topics(const fs::path& bag) {
  const bags::BagInfo info = bags::inspect_bag(bag);
  std::vector<std::string> lines;
  for (const auto& t : info.topics)
    lines.push_back(fmt::format("  {:<40} {:<40} {:>8}", t.name, t.type, t.count));
  return lines;
}

Track import_rosbag(const fs::path& bag, const RosbagImportOptions& o) {
  const bags::BagInfo info = bags::inspect_bag(bag);
  if (info.messages == 0) fail_import(bag, "the bag holds no messages");
  const Topics tp = choose_topics(bag, info, o);
  const BagRead rd = read_streams(bag, info, tp, o);
  Rotation imu_rot = Rotation::Identity();
  std::string imu_rot_note;
  if (!tp.imu.empty()) std::tie(imu_rot, imu_rot_note) = imu_mounting(o, rd);
  std::int64_t t0 = 0;
  TrackData d = fill_rows(tp, rd, imu_rot, &t0);
  add_rosbag_metadata(bag, info, o, tp, rd, imu_rot_note, t0, d.meta);
  try {
    return Track(std::move(d));
  } catch (const std::invalid_argument& e) {
    fail_import(bag, std::string("the imported track is invalid: ") + e.what());
  }
}

}  // namespace odotune::tracks

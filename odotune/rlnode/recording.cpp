#include <odotune/rlnode/recording.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/bags/bag.h>
#include <odotune/bags/ros_messages.h>
#include <odotune/rlnode/input_loader.h>

namespace odotune::rlnode {
namespace {

namespace ros = bags::ros;

std::string_view expected_type(SensorKind k) {
  switch (k) {
    case SensorKind::odom: return "nav_msgs/Odometry";
    case SensorKind::imu: return "sensor_msgs/Imu";
    case SensorKind::pose: return "geometry_msgs/PoseWithCovarianceStamped";
    case SensorKind::twist: return "geometry_msgs/TwistWithCovarianceStamped";
  }
  return "";
}

std::string topic_list(const bags::BagInfo& info) {
  std::string s;
  for (const auto& t : info.topics) s += (s.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  return s;
}

// Which topic feeds which sensor; the odomN whose topic is not in the bag is
// navsat_transform_node's output when the file configures navsat and the bag
// has NavSatFix.
struct TopicPlan {
  std::map<std::string, std::vector<int>> sensors_of;  // topic → sensor indices
  int gps_sensor = -1;
  std::string gps_topic, imu_topic;
  std::string command_topic;  // use_control's cmd_vel, as remapped (empty: none)
};

// The topic the node's subscription to `topic` reads, under --remap.
std::string resolved(const RecordingOptions& options, const std::string& topic) {
  std::string t = detail::with_slash(topic);
  for (const auto& [from, to] : options.remap) {
    if (detail::with_slash(from) == t) return detail::with_slash(to);
  }
  return t;
}

// use_control's commands: the bag's topic for cmd_vel, of the type the node subscribes to.
std::string command_topic(const bags::BagInfo& info, const RlParams& params, const RecordingOptions& options,
                          const std::map<std::string, std::string>& types) {
  if (!params.control.enabled) return "";
  std::string topic = resolved(options, params.control.topic);
  const std::string_view want = params.control.stamped ? "geometry_msgs/TwistStamped" : "geometry_msgs/Twist";
  const auto it = types.find(topic);
  if (it == types.end()) {
    throw std::invalid_argument(fmt::format(
        "{}: use_control: the node's commands ({}) are not in the bag (its topics: {}); expected them, or "
        "--remap {}=TOPIC",
        info.path.string(), topic, topic_list(info), params.control.topic));
  }
  if (it->second != want) {
    throw std::invalid_argument(fmt::format("{}: use_control: {} is {}, expected {}{}", info.path.string(),
                                            topic, it->second, want,
                                            params.ros2 ? "" : " (stamped_control picks TwistStamped)"));
  }
  return topic;
}

TopicPlan plan_topics(const bags::BagInfo& info, const RlParams& params, const RecordingOptions& options) {
  std::map<std::string, std::string> types;
  for (const auto& t : info.topics) types[t.name] = t.type;
  TopicPlan plan;
  for (std::size_t s = 0; s < params.sensors.size(); ++s) {
    const SensorParams& sp = params.sensors[s];
    const std::string topic = resolved(options, sp.topic);
    auto it = types.find(topic);
    if (it == types.end() && sp.kind == SensorKind::odom && params.navsat.present && plan.gps_sensor < 0) {
      plan.gps_sensor = static_cast<int>(s);
      continue;
    }
    if (it == types.end()) {
      throw std::invalid_argument(
          fmt::format("{}: {} topic {} is not in the bag (its topics: {}); expected one "
                      "of them, or --remap {}=TOPIC",
                      info.path.string(), sp.name, topic, topic_list(info), sp.topic));
    }
    if (it->second != expected_type(sp.kind)) {
      throw std::invalid_argument(fmt::format("{}: {} topic {} is {}, expected {}", info.path.string(), sp.name,
                                              topic, it->second, expected_type(sp.kind)));
    }
    if (sp.kind == SensorKind::imu && plan.imu_topic.empty()) plan.imu_topic = topic;
    plan.sensors_of[topic].push_back(static_cast<int>(s));
  }
  plan.command_topic = command_topic(info, params, options, types);
  if (plan.gps_sensor >= 0) {
    const SensorParams& sp = params.sensors[plan.gps_sensor];
    for (int i = 3; i < 15; ++i) {
      if (sp.config[i]) {
        throw std::invalid_argument(
            fmt::format("{}: {} is navsat_transform_node's output; expected only x, y, z "
                        "in {}_config (its orientation and twist are not measured)",
                        params.file.string(), sp.name, sp.name));
      }
    }
    std::vector<std::string> fixes;
    for (const auto& t : info.topics) {
      if (t.type == "sensor_msgs/NavSatFix") fixes.push_back(t.name);
    }
    if (!options.gps_topic.empty()) {
      plan.gps_topic = detail::with_slash(options.gps_topic);
      if (types[plan.gps_topic] != "sensor_msgs/NavSatFix") {
        throw std::invalid_argument(
            fmt::format("{}: --gps-topic {} is not a NavSatFix topic of the bag (its topics: {})",
                        info.path.string(), plan.gps_topic, topic_list(info)));
      }
    } else if (fixes.size() == 1) {
      plan.gps_topic = fixes[0];
    } else {
      throw std::invalid_argument(fmt::format(
          "{}: {} ({}) is navsat_transform_node's output, and the bag has {} NavSatFix topics; expected one, or "
          "--gps-topic",
          info.path.string(), sp.name, sp.topic, fixes.size()));
    }
  }
  return plan;
}

// /tf_static's transforms as poses in base_link, following chains of
// parents up to base_link.
std::map<std::string, Pose3> static_frames(const std::filesystem::path& bag, const bags::BagInfo& info,
                                           const std::string& base) {
  const bool has = std::any_of(info.topics.begin(), info.topics.end(),
                               [](const bags::BagTopic& t) { return t.name == "/tf_static"; });
  std::map<std::string, std::pair<std::string, Pose3>> parent_of;  // child → (parent, child in parent)
  if (has) {
    bags::read_bag(
        bag, [](std::string_view t) { return t == "/tf_static"; },
        [&](const bags::BagMessage& m) {
          for (const auto& tf : ros::decode_tf_message(m.data, m.encoding).transforms) {
            Pose3 p;
            p.t = {tf.translation.x, tf.translation.y, tf.translation.z};
            p.R = rotation_of_quaternion(tf.rotation.x, tf.rotation.y, tf.rotation.z, tf.rotation.w);
            parent_of[tf.child_frame_id] = {tf.header.frame_id, p};
          }
        });
  }
  std::map<std::string, Pose3> frames;
  for (const auto& [child, link] : parent_of) {
    Pose3 pose = link.second;
    std::string parent = link.first;
    for (int depth = 0; parent != base && depth < 32; ++depth) {
      auto up = parent_of.find(parent);
      if (up == parent_of.end()) break;
      pose = {up->second.second.R * pose.t + up->second.second.t, up->second.second.R * pose.R};
      parent = up->second.first;
    }
    if (parent == base) frames[child] = pose;
  }
  return frames;
}

}  // namespace

const std::pair<std::int64_t, double>* navsat_heading_at(const Recording& rec, std::int64_t at) {
  const auto& h = rec.navsat_headings;
  auto it = std::upper_bound(h.begin(), h.end(), at, [](std::int64_t v, const auto& e) { return v < e.first; });
  return it == h.begin() ? nullptr : &*std::prev(it);
}

Recording load_recording(const std::filesystem::path& bag, const RlParams& params,
                         const RecordingOptions& options) {
  if (!(params.frequency_hz >= 1e-3 && params.frequency_hz <= 1e5) || !(params.sensor_timeout_s >= 0.0)) {
    throw std::invalid_argument(
        fmt::format("{}: frequency {} Hz, sensor_timeout {} s: expected 0.001–100000 Hz and "
                    "a timeout ≥ 0",
                    params.file.string(), params.frequency_hz, params.sensor_timeout_s));
  }
  const bags::BagInfo info = bags::inspect_bag(bag);
  const TopicPlan plan = plan_topics(info, params, options);
  Recording rec;
  rec.params = params;
  rec.notes = params.notes;
  rec.bag = bag;
  rec.gps_sensor = plan.gps_sensor;
  rec.gps_topic = plan.gps_topic;
  detail::Loader loader(params, options, rec);
  loader.set_static_frames(static_frames(bag, info, params.base_link_frame));
  if (params.navsat.present && params.navsat.datum) rec.gps_transform = loader.set_datum(*params.navsat.datum);

  std::set<std::string, std::less<>> wanted;
  for (const auto& [topic, s] : plan.sensors_of) wanted.insert(topic);
  if (!plan.gps_topic.empty()) wanted.insert(plan.gps_topic);
  if (!plan.command_topic.empty()) wanted.insert(plan.command_topic);
  const auto from_ns = static_cast<std::int64_t>(std::llround(options.from_s * 1e9));
  bool first = true;
  bags::read_bag(
      bag, [&](std::string_view t) { return wanted.count(t) > 0; },
      [&](const bags::BagMessage& m) {
        if (first) rec.origin_ns = m.receive_time_ns;
        first = false;
        if (m.receive_time_ns < rec.origin_ns + from_ns) return;
        const std::string topic(m.topic);
        if (topic == plan.gps_topic)
          loader.on_fix(ros::decode_navsatfix(m.data, m.encoding), m.receive_time_ns);
        if (topic == plan.command_topic) {
          loader.on_command(params.control.stamped ? ros::decode_twist_stamped(m.data, m.encoding)
                                                   : ros::decode_twist(m.data, m.encoding),
                            m.receive_time_ns);
        }
        auto it = plan.sensors_of.find(topic);
        if (it == plan.sensors_of.end()) return;
        const SensorKind kind = params.sensors[it->second.front()].kind;
        if (kind == SensorKind::odom) {
          const ros::Odometry o = ros::decode_odometry(m.data, m.encoding);
          for (int s : it->second) loader.on_odometry(o, s, m.receive_time_ns);
        } else if (kind == SensorKind::imu) {
          const ros::Imu imu = ros::decode_imu(m.data, m.encoding);
          if (topic == plan.imu_topic && plan.gps_sensor >= 0)
            loader.note_imu_orientation(imu, m.receive_time_ns);
          for (int s : it->second) loader.on_imu(imu, s, m.receive_time_ns);
        } else if (kind == SensorKind::pose) {
          const ros::PoseStamped p = ros::decode_pose_with_covariance_stamped(m.data, m.encoding);
          for (int s : it->second) loader.on_pose(p, s, m.receive_time_ns);
        } else if (kind == SensorKind::twist) {
          const ros::TwistWithCovarianceStamped t = ros::decode_twist_with_covariance_stamped(m.data,
                                                                                              m.encoding);
          for (int s : it->second) loader.on_twist(t, s, m.receive_time_ns);
        }
      });
  loader.finish();
  std::stable_sort(rec.inputs.begin(), rec.inputs.end(),
                   [](const Input& a, const Input& b) { return a.receive_ns < b.receive_ns; });
  std::stable_sort(rec.navsat_headings.begin(), rec.navsat_headings.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  if (rec.inputs.empty()) {
    throw std::invalid_argument(fmt::format("{}: none of the configured inputs has a message in the bag",
                                            bag.string()));
  }
  rec.start_ns = rec.inputs.front().receive_ns;
  rec.end_ns = rec.inputs.back().receive_ns;
  return rec;
}

}  // namespace odotune::rlnode

// One way to read any bag odotune imports: ROS 1 bags (.bag, format 2.0,
// through Debian's librosbag_storage when the build has it), MCAP files
// (ROS 2's default storage, odotune/bags/mcap.h) and rosbag2 SQLite bags (.db3), or a
// rosbag2 folder (metadata.yaml beside its .db3 or .mcap files).
//
// The format is found from the content (magic bytes), not the name.
// Messages come in file order with their receive time (ROS 1 bag time,
// MCAP log_time, rosbag2 timestamp) and their raw bytes and wire encoding,
// for odotune/bags/ros_messages.h to decode. Errors: BagError naming the bag.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/bags/wire.h>

namespace odotune::bags {

enum class BagFormat { ros1, mcap, rosbag2_sqlite };
std::string_view to_string(BagFormat f);  // "ROS 1 bag", "MCAP", "rosbag2 SQLite"

struct BagTopic {
  std::string name;
  std::string type;  // normalised: "nav_msgs/Odometry" (ros::normalise_type)
  std::uint64_t count = 0;
};

struct BagInfo {
  std::filesystem::path path;
  BagFormat format = BagFormat::mcap;
  std::vector<std::filesystem::path> files;  // the storage files read (a rosbag2 folder may have several)
  std::vector<BagTopic> topics;              // in order of first appearance
  std::int64_t start_ns = 0, end_ns = 0;     // receive times of the first and last message
  std::uint64_t messages = 0;
};

struct BagMessage {
  std::string_view topic;
  std::string_view type;  // normalised
  std::int64_t receive_time_ns = 0;
  std::span<const std::uint8_t> data;
  WireEncoding encoding = WireEncoding::cdr;
};

// True when this build reads ROS 1 bags (librosbag_storage was found).
bool ros1_supported();

// Format and topics of a bag (one pass over its messages). Throws BagError.
BagInfo inspect_bag(const std::filesystem::path& path);

// Calls on_message for every message whose topic `want` accepts, in file
// order. Throws BagError (and lets on_message's exceptions through).
void read_bag(const std::filesystem::path& path, const std::function<bool(std::string_view topic)>& want,
              const std::function<void(const BagMessage&)>& on_message);

}  // namespace odotune::bags

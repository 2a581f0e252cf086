// The storage readers behind odotune/bags/bag.h (one per format), for bag.cpp.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

#include <odotune/bags/bag.h>

namespace odotune::bags::detail {

using Want = std::function<bool(std::string_view topic)>;
using OnMessage = std::function<void(const BagMessage&)>;

// An MCAP file (odotune/bags/mcap.h): channel topics, schema names as types,
// message_encoding "cdr" or "ros1".
void read_mcap_bag(const std::filesystem::path& file, const Want& want, const OnMessage& on_message);
// One rosbag2 SQLite file (tables topics and messages), in timestamp order.
void read_sqlite_bag(const std::filesystem::path& file, const Want& want, const OnMessage& on_message);
// A ROS 1 bag through librosbag_storage; throws BagError when the build has
// no ROS 1 support.
void read_ros1_bag(const std::filesystem::path& file, const Want& want, const OnMessage& on_message);

}  // namespace odotune::bags::detail

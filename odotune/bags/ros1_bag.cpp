// A ROS 1 bag (format 2.0) as a bag (odotune/bags/bag_readers.h), read with Debian's
// librosbag_storage (rosbag::Bag and rosbag::View decompress the bz2 and lz4
// chunks and keep the connection table); each message's serialised bytes
// are copied out and decoded by odotune/bags/ros_messages.h like ROS 2's, so the two
// share one decoder. Without librosbag in the build (ODOTUNE_WITH_ROS1 unset)
// a ROS 1 bag is refused with that reason.
#include <odotune/bags/bag_error.h>
#include <odotune/bags/bag_readers.h>
#include <odotune/bags/ros_messages.h>

#ifdef ODOTUNE_WITH_ROS1
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>

#include <vector>
#endif

namespace odotune::bags {

bool ros1_supported() {
#ifdef ODOTUNE_WITH_ROS1
  return true;
#else
  return false;
#endif
}

namespace detail {

void read_ros1_bag(const std::filesystem::path& file, const Want& want, const OnMessage& on_message) {
#ifdef ODOTUNE_WITH_ROS1
  const std::string name = file.string();
  try {
    rosbag::Bag bag;
    bag.open(name, rosbag::bagmode::Read);
    rosbag::View view(bag, [&](const rosbag::ConnectionInfo* c) { return want(c->topic); });
    std::vector<std::uint8_t> buf;
    std::string topic, type;
    for (const rosbag::MessageInstance& m : view) {
      buf.resize(m.size());
      ::ros::serialization::OStream out(buf.data(), static_cast<std::uint32_t>(buf.size()));
      m.write(out);
      topic = m.getTopic();
      type = bags::ros::normalise_type(m.getDataType());  // odotune's, not ROS 1's ::ros
      BagMessage msg;
      msg.topic = topic;
      msg.type = type;
      const ::ros::Time t = m.getTime();
      msg.receive_time_ns = static_cast<std::int64_t>(t.sec) * 1000000000LL + t.nsec;
      msg.data = buf;
      msg.encoding = WireEncoding::ros1;
      on_message(msg);
    }
  } catch (const rosbag::BagException& e) {
    throw BagError(name, "", std::string("ROS 1 bag: ") + e.what());
  }
#else
  (void)want;
  (void)on_message;
  throw BagError(file.string(), "",
                 "this is a ROS 1 bag, and this odotune was built without ROS 1 support (install "
                 "librosbag-storage-dev with scripts/install-deps.sh and rebuild)");
#endif
}

}  // namespace detail
}  // namespace odotune::bags

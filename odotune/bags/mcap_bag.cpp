// MCAP as a bag (odotune/bags/bag_readers.h): messages in file order with their
// channel's topic and schema name.
#include <map>

#include <odotune/bags/bag_error.h>
#include <odotune/bags/bag_readers.h>
#include <odotune/bags/mcap.h>
#include <odotune/bags/ros_messages.h>

namespace odotune::bags::detail {

void read_mcap_bag(const std::filesystem::path& file, const Want& want, const OnMessage& on_message) {
  mcap::StreamReader reader(file);
  std::map<std::uint16_t, std::string> schema_names;
  struct ChannelInfo {
    std::string topic, type;
    WireEncoding encoding = WireEncoding::cdr;
    bool wanted = false;
    bool supported = true;
    std::string encoding_name;
  };
  std::map<std::uint16_t, ChannelInfo> channels;
  while (auto rec = reader.next()) {
    if (const auto* s = std::get_if<mcap::Schema>(&*rec)) {
      schema_names[s->id] = s->name;
    } else if (const auto* c = std::get_if<mcap::Channel>(&*rec)) {
      ChannelInfo info;
      info.topic = c->topic;
      const auto sn = schema_names.find(c->schema_id);
      info.type = ros::normalise_type(sn == schema_names.end() ? std::string() : sn->second);
      info.encoding_name = c->message_encoding;
      info.supported = c->message_encoding == "cdr" || c->message_encoding == "ros1";
      info.encoding = c->message_encoding == "ros1" ? WireEncoding::ros1 : WireEncoding::cdr;
      info.wanted = want(info.topic);
      channels[c->id] = std::move(info);
    } else if (const auto* m = std::get_if<mcap::Message>(&*rec)) {
      const ChannelInfo& ch = channels.at(m->channel_id);  // the reader checked it exists
      if (!ch.wanted) continue;
      if (!ch.supported)
        throw BagError(file.string(), "topic " + ch.topic,
                       "message encoding '" + ch.encoding_name + "' is not supported (expected cdr or ros1)");
      BagMessage msg;
      msg.topic = ch.topic;
      msg.type = ch.type;
      msg.receive_time_ns = static_cast<std::int64_t>(m->log_time);
      msg.data = m->data;
      msg.encoding = ch.encoding;
      on_message(msg);
    }
  }
}

}  // namespace odotune::bags::detail

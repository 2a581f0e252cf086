// A rosbag2 SQLite storage file as a bag (odotune/bags/bag_readers.h): the Humble
// layout (tables topics(id, name, type, serialization_format, ...) and
// messages(id, topic_id, timestamp, data), timestamps in ns), read with
// Debian's SQLite, in timestamp order (ties by row id, the insertion order).
#include <sqlite3.h>

#include <map>
#include <memory>

#include <odotune/bags/bag_error.h>
#include <odotune/bags/bag_readers.h>
#include <odotune/bags/ros_messages.h>

namespace odotune::bags::detail {
namespace {

struct DbCloser {
  void operator()(sqlite3* db) const { sqlite3_close(db); }
};
struct StmtCloser {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};

}  // namespace

void read_sqlite_bag(const std::filesystem::path& file, const Want& want, const OnMessage& on_message) {
  const std::string name = file.string();
  sqlite3* raw = nullptr;
  if (sqlite3_open_v2(name.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    const std::string why = raw ? sqlite3_errmsg(raw) : "cannot open";
    sqlite3_close(raw);
    throw BagError(name, "", "cannot open the SQLite bag: " + why);
  }
  std::unique_ptr<sqlite3, DbCloser> db(raw);
  auto prepare = [&](const char* sql) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db.get(), sql, -1, &s, nullptr) != SQLITE_OK)
      throw BagError(name, "",
                     std::string("not a rosbag2 SQLite bag (") + sqlite3_errmsg(db.get()) +
                         "; expected the tables topics and messages)");
    return std::unique_ptr<sqlite3_stmt, StmtCloser>(s);
  };
  struct Topic {
    std::string name, type;
    WireEncoding encoding = WireEncoding::cdr;
    bool wanted = false;
  };
  std::map<std::int64_t, Topic> topics;
  {
    auto st = prepare("SELECT id, name, type, serialization_format FROM topics");
    int rc = 0;
    while ((rc = sqlite3_step(st.get())) == SQLITE_ROW) {
      Topic t;
      auto text = [&](int col) {
        const auto* p = sqlite3_column_text(st.get(), col);
        return p ? std::string(reinterpret_cast<const char*>(p)) : std::string();
      };
      t.name = text(1);
      t.type = ros::normalise_type(text(2));
      const std::string fmt = text(3);
      if (fmt != "cdr" && fmt != "ros1")
        throw BagError(name, "topic " + t.name,
                       "serialization_format '" + fmt + "' is not supported (expected cdr or ros1)");
      t.encoding = fmt == "ros1" ? WireEncoding::ros1 : WireEncoding::cdr;
      t.wanted = want(t.name);
      topics[sqlite3_column_int64(st.get(), 0)] = std::move(t);
    }
    if (rc != SQLITE_DONE) throw BagError(name, "table topics", sqlite3_errmsg(db.get()));
  }
  auto st = prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id");
  int rc = 0;
  std::int64_t row = 0;
  while ((rc = sqlite3_step(st.get())) == SQLITE_ROW) {
    ++row;
    const std::int64_t topic_id = sqlite3_column_int64(st.get(), 0);
    const auto t = topics.find(topic_id);
    if (t == topics.end())
      throw BagError(name, "message " + std::to_string(row),
                     "topic_id " + std::to_string(topic_id) + " is not in the topics table");
    if (!t->second.wanted) continue;
    BagMessage msg;
    msg.topic = t->second.name;
    msg.type = t->second.type;
    msg.receive_time_ns = sqlite3_column_int64(st.get(), 1);
    const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(st.get(), 2));
    const int n = sqlite3_column_bytes(st.get(), 2);
    msg.data = std::span<const std::uint8_t>(blob, blob ? static_cast<std::size_t>(n) : 0);
    msg.encoding = t->second.encoding;
    on_message(msg);
  }
  if (rc != SQLITE_DONE) throw BagError(name, "table messages", sqlite3_errmsg(db.get()));
}

}  // namespace odotune::bags::detail

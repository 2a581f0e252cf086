#include <odotune/bags/bag.h>

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstring>
#include <fstream>
#include <map>

#include <odotune/bags/bag_error.h>
#include <odotune/bags/bag_readers.h>

namespace odotune::bags {
namespace {

namespace fs = std::filesystem;

// The storage format of one file, from its first bytes.
BagFormat sniff(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw BagError(file.string(), "", "cannot open the file");
  std::array<char, 16> head{};
  in.read(head.data(), head.size());
  const auto n = static_cast<std::size_t>(in.gcount());
  const std::string_view h(head.data(), n);
  if (h.starts_with("#ROSBAG V2.0")) return BagFormat::ros1;
  if (h.starts_with("#ROSBAG")) throw BagError(file.string(), "", "ROS 1 bag of a version other than 2.0");
  if (n >= 5 && static_cast<unsigned char>(h[0]) == 0x89 && h.substr(1, 4) == "MCAP") return BagFormat::mcap;
  if (h.starts_with(std::string_view("SQLite format 3\0", 16))) return BagFormat::rosbag2_sqlite;
  throw BagError(file.string(), "",
                 "not a bag (expected a ROS 1 bag, an MCAP file, a rosbag2 .db3 file or a rosbag2 folder)");
}

// The storage files of a bag path: a rosbag2 folder lists them in its
// metadata.yaml (relative_file_paths); a file is itself.
std::vector<fs::path> storage_files(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) {
    if (!fs::exists(path, ec)) throw BagError(path.string(), "", "no such file or folder");
    return {path};
  }
  const fs::path meta = path / "metadata.yaml";
  if (!fs::exists(meta, ec))
    throw BagError(path.string(), "", "a folder without metadata.yaml (expected a rosbag2 bag folder)");
  std::vector<fs::path> files;
  try {
    const YAML::Node root = YAML::LoadFile(meta.string());
    const YAML::Node info = root["rosbag2_bagfile_information"];
    if (!info || !info["relative_file_paths"] || !info["relative_file_paths"].IsSequence())
      throw BagError(meta.string(), "", "no rosbag2_bagfile_information.relative_file_paths list");
    if (info["compression_format"] && !info["compression_format"].as<std::string>().empty())
      throw BagError(meta.string(), "",
                     "compression_format '" + info["compression_format"].as<std::string>() +
                         "' (file-level compression) is not supported (expected \"\"; MCAP's own chunk "
                         "compression is)");
    for (const auto& f : info["relative_file_paths"]) files.push_back(path / f.as<std::string>());
  } catch (const YAML::Exception& e) {
    throw BagError(meta.string(), "line " + std::to_string(e.mark.line + 1), e.msg);
  }
  if (files.empty()) throw BagError(meta.string(), "", "relative_file_paths is empty");
  for (const auto& f : files)
    if (!fs::exists(f, ec)) throw BagError(meta.string(), "", "lists " + f.string() + ", which does not exist");
  return files;
}

void read_file(const fs::path& file, BagFormat format, const detail::Want& want, const detail::OnMessage& on) {
  switch (format) {
    case BagFormat::ros1: detail::read_ros1_bag(file, want, on); break;
    case BagFormat::mcap: detail::read_mcap_bag(file, want, on); break;
    case BagFormat::rosbag2_sqlite: detail::read_sqlite_bag(file, want, on); break;
  }
}

}  // namespace

std::string_view to_string(BagFormat f) {
  switch (f) {
    case BagFormat::ros1: return "ROS 1 bag";
    case BagFormat::mcap: return "MCAP";
    case BagFormat::rosbag2_sqlite: return "rosbag2 SQLite";
  }
  return "?";
}

void read_bag(const fs::path& path, const std::function<bool(std::string_view topic)>& want,
              const std::function<void(const BagMessage&)>& on_message) {
  for (const fs::path& f : storage_files(path)) read_file(f, sniff(f), want, on_message);
}

BagInfo inspect_bag(const fs::path& path) {
  BagInfo info;
  info.path = path;
  info.files = storage_files(path);
  std::map<std::string, std::size_t, std::less<>> index;
  bool first = true;
  for (const fs::path& f : info.files) {
    const BagFormat format = sniff(f);
    if (f == info.files.front()) info.format = format;
    read_file(
        f, format, [](std::string_view) { return true; },
        [&](const BagMessage& m) {
          auto it = index.find(m.topic);
          if (it == index.end()) {
            it = index.emplace(std::string(m.topic), info.topics.size()).first;
            info.topics.push_back({std::string(m.topic), std::string(m.type), 0});
          }
          ++info.topics[it->second].count;
          if (first || m.receive_time_ns < info.start_ns) info.start_ns = m.receive_time_ns;
          if (first || m.receive_time_ns > info.end_ns) info.end_ns = m.receive_time_ns;
          first = false;
          ++info.messages;
        });
  }
  return info;
}

}  // namespace odotune::bags

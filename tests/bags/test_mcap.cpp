// The MCAP reader (odotune/bags/mcap.h) against the MCAP project's conformance files
// (../shared/data/mcap-conformance, SOURCE.md there): every file reads to the
// records of its .json, in order, field by field. The .mcap files there are
// Git LFS pointers, so each is rebuilt from its .json and name
// (support/mcap_writer.h, which explains why that still checks the
// layout); a real .mcap, where one is present, is read too and must equal the
// rebuilt bytes. Then damaged files (cut, flipped bytes) give one BagError
// and never a crash or hang.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include <odotune/bags/bag_error.h>
#include <odotune/bags/mcap.h>

#include "support/mcap_writer.h"

namespace odotune::bags::mcap {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kConformance = fs::path(ODOTUNE_SHARED_DIR) / "data" / "mcap-conformance";

json bytes_json(const Bytes& b) {
  json a = json::array();
  for (const std::uint8_t x : b) a.push_back(std::to_string(x));
  return a;
}
template <class Map>
json map_json(const Map& m) {
  json o = json::object();
  for (const auto& [k, v] : m) {
    if constexpr (std::is_same_v<Map, StringMap>)
      o[k] = v;
    else
      o[std::to_string(k)] = std::to_string(v);
  }
  return o;
}
std::string n(std::uint64_t x) { return std::to_string(x); }

// A record as the conformance JSON writes it: {"type": ..., "fields": {name: value}}.
json to_json(const Record& rec) {
  json f = json::object();
  std::visit(
      [&](const auto& r) {
        using T = std::decay_t<decltype(r)>;
        if constexpr (std::is_same_v<T, Header>) {
          f = {{"profile", r.profile}, {"library", r.library}};
        } else if constexpr (std::is_same_v<T, Footer>) {
          f = {{"summary_start", n(r.summary_start)},
               {"summary_offset_start", n(r.summary_offset_start)},
               {"summary_crc", n(r.summary_crc)}};
        } else if constexpr (std::is_same_v<T, Schema>) {
          f = {{"id", n(r.id)}, {"name", r.name}, {"encoding", r.encoding}, {"data", bytes_json(r.data)}};
        } else if constexpr (std::is_same_v<T, Channel>) {
          f = {{"id", n(r.id)},
               {"schema_id", n(r.schema_id)},
               {"topic", r.topic},
               {"message_encoding", r.message_encoding},
               {"metadata", map_json(r.metadata)}};
        } else if constexpr (std::is_same_v<T, Message>) {
          f = {{"channel_id", n(r.channel_id)},
               {"sequence", n(r.sequence)},
               {"log_time", n(r.log_time)},
               {"publish_time", n(r.publish_time)},
               {"data", bytes_json(r.data)}};
        } else if constexpr (std::is_same_v<T, ChunkIndex>) {
          f = {{"message_start_time", n(r.message_start_time)},
               {"message_end_time", n(r.message_end_time)},
               {"chunk_start_offset", n(r.chunk_start_offset)},
               {"chunk_length", n(r.chunk_length)},
               {"message_index_offsets", map_json(r.message_index_offsets)},
               {"message_index_length", n(r.message_index_length)},
               {"compression", r.compression},
               {"compressed_size", n(r.compressed_size)},
               {"uncompressed_size", n(r.uncompressed_size)}};
        } else if constexpr (std::is_same_v<T, Attachment>) {
          f = {{"log_time", n(r.log_time)},  {"create_time", n(r.create_time)}, {"name", r.name},
               {"media_type", r.media_type}, {"data", bytes_json(r.data)},      {"crc", n(r.crc)}};
        } else if constexpr (std::is_same_v<T, AttachmentIndex>) {
          f = {{"offset", n(r.offset)},           {"length", n(r.length)},       {"log_time", n(r.log_time)},
               {"create_time", n(r.create_time)}, {"data_size", n(r.data_size)}, {"name", r.name},
               {"media_type", r.media_type}};
        } else if constexpr (std::is_same_v<T, Statistics>) {
          f = {{"message_count", n(r.message_count)},
               {"schema_count", n(r.schema_count)},
               {"channel_count", n(r.channel_count)},
               {"attachment_count", n(r.attachment_count)},
               {"metadata_count", n(r.metadata_count)},
               {"chunk_count", n(r.chunk_count)},
               {"message_start_time", n(r.message_start_time)},
               {"message_end_time", n(r.message_end_time)},
               {"channel_message_counts", map_json(r.channel_message_counts)}};
        } else if constexpr (std::is_same_v<T, Metadata>) {
          f = {{"name", r.name}, {"metadata", map_json(r.metadata)}};
        } else if constexpr (std::is_same_v<T, MetadataIndex>) {
          f = {{"offset", n(r.offset)}, {"length", n(r.length)}, {"name", r.name}};
        } else if constexpr (std::is_same_v<T, SummaryOffset>) {
          f = {{"group_opcode", n(r.group_opcode)},
               {"group_start", n(r.group_start)},
               {"group_length", n(r.group_length)}};
        } else if constexpr (std::is_same_v<T, DataEnd>) {
          f = {{"data_section_crc", n(r.data_section_crc)}};
        }
      },
      rec);
  return {{"type", record_name(rec)}, {"fields", f}};
}

// The expected records of NAME.json, fields as an object.
std::vector<json> expected(const fs::path& json_path) {
  std::ifstream in(json_path);
  const json j = json::parse(in);
  std::vector<json> out;
  for (const auto& r : j.at("records")) {
    json f = json::object();
    for (const auto& kv : r.at("fields")) f[kv.at(0).get<std::string>()] = kv.at(1);
    out.push_back({{"type", r.at("type")}, {"fields", f}});
  }
  return out;
}

Bytes bytes_of(const json& a) {
  Bytes b;
  for (const auto& x : a) b.push_back(static_cast<std::uint8_t>(std::stoul(x.get<std::string>())));
  return b;
}
std::uint64_t u(const json& f, const char* k) { return std::stoull(f.at(k).get<std::string>()); }
StringMap string_map_of(const json& o) {
  StringMap m;
  for (const auto& [k, v] : o.items()) m.emplace_back(k, v.get<std::string>());
  return m;
}

// The data records of an expected list (between Header and DataEnd).
std::vector<Record> data_records(const std::vector<json>& want) {
  std::vector<Record> out;
  for (const json& r : want) {
    const std::string type = r.at("type");
    const json& f = r.at("fields");
    if (type == "DataEnd") break;
    if (type == "Schema") {
      out.push_back(Schema{static_cast<std::uint16_t>(u(f, "id")), f.at("name"), f.at("encoding"),
                           bytes_of(f.at("data"))});
    } else if (type == "Channel") {
      out.push_back(Channel{static_cast<std::uint16_t>(u(f, "id")),
                            static_cast<std::uint16_t>(u(f, "schema_id")), f.at("topic"),
                            f.at("message_encoding"), string_map_of(f.at("metadata"))});
    } else if (type == "Message") {
      out.push_back(Message{static_cast<std::uint16_t>(u(f, "channel_id")),
                            static_cast<std::uint32_t>(u(f, "sequence")), u(f, "log_time"),
                            u(f, "publish_time"), bytes_of(f.at("data"))});
    } else if (type == "Attachment") {
      out.push_back(Attachment{u(f, "log_time"), u(f, "create_time"), f.at("name"), f.at("media_type"),
                               bytes_of(f.at("data")), static_cast<std::uint32_t>(u(f, "crc"))});
    } else if (type == "Metadata") {
      out.push_back(Metadata{f.at("name"), string_map_of(f.at("metadata"))});
    }
  }
  return out;
}

std::vector<fs::path> conformance_jsons() {
  std::vector<fs::path> files;
  if (!fs::exists(kConformance)) return files;
  for (const auto& e : fs::recursive_directory_iterator(kConformance))
    if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::uint8_t> slurp(const fs::path& p);
void spit(const fs::path& p, const std::vector<std::uint8_t>& b);

TEST(Mcap, EveryConformanceFileReadsToItsRecords) {
  const auto files = conformance_jsons();
  ASSERT_GE(files.size(), 380u) << "expected the conformance files under " << kConformance;
  const fs::path tmp = fs::temp_directory_path() / "odotune_mcap_conformance.mcap";
  std::size_t messages = 0, real_files = 0;
  for (const fs::path& f : files) {
    SCOPED_TRACE(f.filename().string());
    const std::vector<json> want = expected(f);
    const auto bytes = testing::conformance_file(testing::features_of(f.stem().string()), data_records(want));
    spit(tmp, bytes);
    std::vector<Record> got;
    ASSERT_NO_THROW(got = read_records(tmp));
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(to_json(got[i]), want[i]) << "record " << i;
      messages += std::holds_alternative<Message>(got[i]);
    }
    const fs::path real = fs::path(f).replace_extension(".mcap");
    const auto real_bytes = slurp(real);
    if (real_bytes.size() > 4 && real_bytes[0] == 0x89) {  // not an LFS pointer
      ++real_files;
      EXPECT_EQ(real_bytes, bytes);
      ASSERT_NO_THROW(got = read_records(real));
      ASSERT_EQ(got.size(), want.size());
      for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(to_json(got[i]), want[i]) << "record " << i;
    }
  }
  fs::remove(tmp);
  EXPECT_GE(messages, 1000u);  // the OneMessage and TenMessages families
  RecordProperty("real_mcap_files", static_cast<int>(real_files));
}

std::vector<std::uint8_t> slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void spit(const fs::path& p, const std::vector<std::uint8_t>& b) {
  std::ofstream out(p, std::ios::binary);
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

// A conformance file rebuilt from its .json (the .mcap is an LFS pointer).
std::vector<std::uint8_t> rebuilt(const std::string& folder, const std::string& stem) {
  const std::vector<json> want = expected(kConformance / folder / (stem + ".json"));
  return testing::conformance_file(testing::features_of(stem), data_records(want));
}

// Reads a damaged copy; true when it gave a BagError naming the file (false
// when it read without complaint). Anything else fails the test.
bool rejects(const fs::path& p) {
  try {
    read_records(p);
    return false;
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return true;
  }
}

TEST(Mcap, TruncatedFilesAreRejectedWithTheirName) {
  const auto bytes = rebuilt("TenMessages", "TenMessages-ch-chx-mx-pad-rch-rsh-st-sum");
  ASSERT_GT(bytes.size(), 1000u);
  const fs::path tmp = fs::temp_directory_path() / "odotune_mcap_cut.mcap";
  for (std::size_t cut = 0; cut < bytes.size(); cut += 7) {
    spit(tmp, std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(cut)));
    EXPECT_TRUE(rejects(tmp)) << "cut at " << cut;
  }
  fs::remove(tmp);
}

TEST(Mcap, FlippedBytesNeverCrash) {
  // Chunked files carry CRCs: a flipped byte in a chunk or the data section is
  // caught. Elsewhere (e.g. a summary string) the file may still read; the
  // contract is one clear error or a result, never a crash.
  const auto bytes = rebuilt("TenMessages", "TenMessages-ch-chx-mx-pad-rch-rsh-st-sum");
  ASSERT_GT(bytes.size(), 1000u);
  const fs::path tmp = fs::temp_directory_path() / "odotune_mcap_flip.mcap";
  std::uint64_t state = 7;
  int rejected = 0;
  for (int trial = 0; trial < 400; ++trial) {
    auto b = bytes;
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const std::size_t at = static_cast<std::size_t>(state >> 33) % b.size();
    b[at] ^= static_cast<std::uint8_t>(1u << ((state >> 20) & 7));
    spit(tmp, b);
    rejected += rejects(tmp);
  }
  fs::remove(tmp);
  EXPECT_GT(rejected, 200);
}

TEST(Mcap, NamesWhatIsWrong) {
  const fs::path tmp = fs::temp_directory_path() / "odotune_mcap_bad.mcap";
  spit(tmp, {'n', 'o', 't', ' ', 'm', 'c', 'a', 'p', '!', '!'});
  try {
    read_records(tmp);
    ADD_FAILURE() << "read a non-MCAP file";
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find("not an MCAP file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_records(fs::temp_directory_path() / "odotune_no_such.mcap"), BagError);
  fs::remove(tmp);
}

}  // namespace
}  // namespace odotune::bags::mcap

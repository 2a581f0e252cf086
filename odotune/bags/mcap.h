// MCAP (https://mcap.dev/spec, major version 0): the container of ROS 2 bags
// (rosbag2's default storage since Iron) and of Foxglove recordings.
//
// Why our own reader: Debian 12 packages no MCAP library, and the format is a
// flat sequence of length-prefixed records; this reader is the spec's record
// table and nothing else. It is tested against the MCAP project's conformance
// files (../shared/data/mcap-conformance: every file reads to the records of
// its .json) and on randomly mutated files (never a crash or hang).
//
// Reading is streamed, record by record, in file order, the way the
// conformance "streamed" readers work: a Chunk's records are decompressed
// and returned in place of the Chunk; Chunk and MessageIndex records
// themselves are not returned (they are containers and indexes of what is
// returned); records of unknown opcodes are skipped (the spec reserves them
// for extensions); bytes after a record's known fields (padding, fields of a
// later minor version) are ignored. The reader checks the leading and
// trailing magic, that every record length fits in the file, each Chunk's
// uncompressed size and CRC-32 (when not 0), the data section's CRC-32 (when
// DataEnd gives one), that a Message's channel and a Channel's schema were
// defined before it, and the record order (Header first, Footer last).
// Chunks may be uncompressed, "zstd" or "lz4" (the lz4 frame format), read
// with Debian's libzstd and liblz4; a chunk declaring more than 1 GiB
// uncompressed is refused (a decompression bomb is not a bag).
//
// Errors: BagError (odotune/bags/bag_error.h) naming the file and the byte offset.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace odotune::bags::mcap {

enum class Opcode : std::uint8_t {
  header = 0x01,
  footer = 0x02,
  schema = 0x03,
  channel = 0x04,
  message = 0x05,
  chunk = 0x06,
  message_index = 0x07,
  chunk_index = 0x08,
  attachment = 0x09,
  attachment_index = 0x0a,
  statistics = 0x0b,
  metadata = 0x0c,
  metadata_index = 0x0d,
  summary_offset = 0x0e,
  data_end = 0x0f,
};

// Maps keep the file's order (the spec's maps are written sorted by key).
using StringMap = std::vector<std::pair<std::string, std::string>>;
using U16U64Map = std::vector<std::pair<std::uint16_t, std::uint64_t>>;
using Bytes = std::vector<std::uint8_t>;

struct Header {
  std::string profile, library;
};
struct Footer {
  std::uint64_t summary_start = 0, summary_offset_start = 0;
  std::uint32_t summary_crc = 0;
};
struct Schema {
  std::uint16_t id = 0;
  std::string name, encoding;
  Bytes data;
};
struct Channel {
  std::uint16_t id = 0, schema_id = 0;  // schema_id 0: no schema
  std::string topic, message_encoding;
  StringMap metadata;
};
struct Message {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0, publish_time = 0;  // [ns]
  Bytes data;
};
struct ChunkIndex {
  std::uint64_t message_start_time = 0, message_end_time = 0, chunk_start_offset = 0, chunk_length = 0;
  U16U64Map message_index_offsets;
  std::uint64_t message_index_length = 0;
  std::string compression;
  std::uint64_t compressed_size = 0, uncompressed_size = 0;
};
struct Attachment {
  std::uint64_t log_time = 0, create_time = 0;
  std::string name, media_type;
  Bytes data;
  std::uint32_t crc = 0;
};
struct AttachmentIndex {
  std::uint64_t offset = 0, length = 0, log_time = 0, create_time = 0, data_size = 0;
  std::string name, media_type;
};
struct Statistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0, attachment_count = 0, metadata_count = 0, chunk_count = 0;
  std::uint64_t message_start_time = 0, message_end_time = 0;
  U16U64Map channel_message_counts;
};
struct Metadata {
  std::string name;
  StringMap metadata;
};
struct MetadataIndex {
  std::uint64_t offset = 0, length = 0;
  std::string name;
};
struct SummaryOffset {
  std::uint8_t group_opcode = 0;
  std::uint64_t group_start = 0, group_length = 0;
};
struct DataEnd {
  std::uint32_t data_section_crc = 0;
};

using Record = std::variant<Header, Footer, Schema, Channel, Message, ChunkIndex, Attachment, AttachmentIndex,
                            Statistics, Metadata, MetadataIndex, SummaryOffset, DataEnd>;

// The record's name as the spec writes it ("Header", "ChunkIndex", ...).
const char* record_name(const Record& r);

class StreamReader {
 public:
  // Opens the file and checks the leading magic. Throws BagError.
  explicit StreamReader(const std::filesystem::path& path);

  // The next record (see the header comment), or nullopt after the Footer
  // and the trailing magic. Throws BagError on anything malformed.
  std::optional<Record> next();

  const std::filesystem::path& path() const { return path_; }

 private:
  std::optional<Record> next_in_chunk();
  Record parse(std::uint8_t opcode, const Bytes& content, std::uint64_t offset, bool in_chunk);
  void read_exact(void* out, std::uint64_t n, std::uint64_t offset, const char* what);
  [[noreturn]] void fail(std::uint64_t offset, const std::string& reason) const;

  std::filesystem::path path_;
  std::string name_;  // path as text, for messages
  std::ifstream in_;
  std::uint64_t size_ = 0;  // file size [bytes]
  std::uint64_t pos_ = 0;   // next record's offset
  bool seen_header_ = false, seen_footer_ = false, seen_data_end_ = false, finished_ = false;
  std::uint32_t data_crc_ = 0;  // running CRC-32 of the data section
  std::vector<bool> schema_defined_ = std::vector<bool>(65536, false);
  std::vector<bool> channel_defined_ = std::vector<bool>(65536, false);
  // The decompressed records of the Chunk being read, and the position in them.
  Bytes chunk_;
  std::size_t chunk_pos_ = 0;
  std::uint64_t chunk_offset_ = 0;  // the Chunk record's offset in the file
};

// Every record of the file (StreamReader::next until the end).
std::vector<Record> read_records(const std::filesystem::path& path);

}  // namespace odotune::bags::mcap

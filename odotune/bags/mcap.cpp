#include <odotune/bags/mcap.h>

#include <array>
#include <cstring>
#include <span>
#include <system_error>

#include <odotune/bags/bag_error.h>
#include <odotune/bags/byte_reader.h>
#include <odotune/bags/compression.h>

namespace odotune::bags::mcap {
namespace {

constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 30;  // 1 GiB uncompressed
constexpr std::size_t kRecordHeaderBytes = 9;                     // opcode u8 + length u64

std::string str(ByteReader& r, const char* field) {
  const std::uint32_t n = r.u32(field);
  return std::string(r.text(n, field));
}

Bytes bytes_u32(ByteReader& r, const char* field) {
  const std::uint32_t n = r.u32(field);
  const auto b = r.bytes(n, field);
  return Bytes(b.begin(), b.end());
}

StringMap string_map(ByteReader& r, const char* field) {
  const std::uint32_t n = r.u32(field);
  ByteReader m(r.bytes(n, field));
  StringMap out;
  while (!m.done()) {
    std::string k = str(m, field);
    std::string v = str(m, field);
    out.emplace_back(std::move(k), std::move(v));
  }
  return out;
}

U16U64Map u16_u64_map(ByteReader& r, const char* field) {
  const std::uint32_t n = r.u32(field);
  ByteReader m(r.bytes(n, field));
  U16U64Map out;
  while (!m.done()) {
    const std::uint16_t k = m.u16(field);
    const std::uint64_t v = m.u64(field);
    out.emplace_back(k, v);
  }
  return out;
}

const char* opcode_name(std::uint8_t op) {
  static constexpr const char* kNames[] = {"?",          "Header",        "Footer",          "Schema",
                                           "Channel",    "Message",       "Chunk",           "MessageIndex",
                                           "ChunkIndex", "Attachment",    "AttachmentIndex", "Statistics",
                                           "Metadata",   "MetadataIndex", "SummaryOffset",   "DataEnd"};
  return op >= 1 && op <= 0x0f ? kNames[op] : "unknown record";
}

bool known(std::uint8_t op) { return op >= 0x01 && op <= 0x0f; }

// A Chunk record's records, decompressed into `chunk` and checked against
// its CRC-32; `fail` throws with the reason (the caller adds the record's offset).
template <class Fail>
void read_chunk(const Bytes& content, Bytes& chunk, Fail&& fail) {
  ByteReader r(content);
  try {
    r.u64("message_start_time");
    r.u64("message_end_time");
    const std::uint64_t uncompressed_size = r.u64("uncompressed_size");
    const std::uint32_t uncompressed_crc = r.u32("uncompressed_crc");
    const std::string compression = str(r, "compression");
    const std::uint64_t n = r.u64("records length");
    const auto records = r.bytes(n, "records");
    if (uncompressed_size > kMaxChunkBytes)
      fail("Chunk declares " + std::to_string(uncompressed_size) +
           " bytes uncompressed (more than the 1 GiB this reader accepts)");
    try {
      chunk = decompress(compression, records, uncompressed_size);
    } catch (const std::runtime_error& e) {
      fail(std::string("Chunk: ") + e.what());
    }
    if (uncompressed_crc != 0 && crc32(chunk) != uncompressed_crc)
      fail("Chunk: CRC-32 of its records does not match (the chunk is corrupt)");
  } catch (const ByteReader::Short& e) {
    fail(std::string("Chunk: ") + e.what());
  }
}

// The records without state to check, read field by field (ByteReader::Short
// when one is cut off).
Header read_header(ByteReader& r) {
  Header h;
  h.profile = str(r, "profile");
  h.library = str(r, "library");
  return h;
}

Footer read_footer(ByteReader& r) {
  Footer f;
  f.summary_start = r.u64("summary_start");
  f.summary_offset_start = r.u64("summary_offset_start");
  f.summary_crc = r.u32("summary_crc");
  return f;
}

ChunkIndex read_chunk_index(ByteReader& r) {
  ChunkIndex c;
  c.message_start_time = r.u64("message_start_time");
  c.message_end_time = r.u64("message_end_time");
  c.chunk_start_offset = r.u64("chunk_start_offset");
  c.chunk_length = r.u64("chunk_length");
  c.message_index_offsets = u16_u64_map(r, "message_index_offsets");
  c.message_index_length = r.u64("message_index_length");
  c.compression = str(r, "compression");
  c.compressed_size = r.u64("compressed_size");
  c.uncompressed_size = r.u64("uncompressed_size");
  return c;
}

Attachment read_attachment(ByteReader& r) {
  Attachment a;
  a.log_time = r.u64("log_time");
  a.create_time = r.u64("create_time");
  a.name = str(r, "name");
  a.media_type = str(r, "media_type");
  const std::uint64_t n = r.u64("data length");
  const auto d = r.bytes(n, "data");
  a.data.assign(d.begin(), d.end());
  a.crc = r.u32("crc");
  return a;
}

AttachmentIndex read_attachment_index(ByteReader& r) {
  AttachmentIndex a;
  a.offset = r.u64("offset");
  a.length = r.u64("length");
  a.log_time = r.u64("log_time");
  a.create_time = r.u64("create_time");
  a.data_size = r.u64("data_size");
  a.name = str(r, "name");
  a.media_type = str(r, "media_type");
  return a;
}

Statistics read_statistics(ByteReader& r) {
  Statistics s;
  s.message_count = r.u64("message_count");
  s.schema_count = r.u16("schema_count");
  s.channel_count = r.u32("channel_count");
  s.attachment_count = r.u32("attachment_count");
  s.metadata_count = r.u32("metadata_count");
  s.chunk_count = r.u32("chunk_count");
  s.message_start_time = r.u64("message_start_time");
  s.message_end_time = r.u64("message_end_time");
  s.channel_message_counts = u16_u64_map(r, "channel_message_counts");
  return s;
}

Metadata read_metadata(ByteReader& r) {
  Metadata m;
  m.name = str(r, "name");
  m.metadata = string_map(r, "metadata");
  return m;
}

MetadataIndex read_metadata_index(ByteReader& r) {
  MetadataIndex m;
  m.offset = r.u64("offset");
  m.length = r.u64("length");
  m.name = str(r, "name");
  return m;
}

SummaryOffset read_summary_offset(ByteReader& r) {
  SummaryOffset s;
  s.group_opcode = r.u8("group_opcode");
  s.group_start = r.u64("group_start");
  s.group_length = r.u64("group_length");
  return s;
}

DataEnd read_data_end(ByteReader& r) {
  DataEnd d;
  d.data_section_crc = r.u32("data_section_crc");
  return d;
}

}  // namespace

const char* record_name(const Record& r) {
  static constexpr const char* kNames[] = {
      "Header",          "Footer",     "Schema",   "Channel",       "Message",       "ChunkIndex", "Attachment",
      "AttachmentIndex", "Statistics", "Metadata", "MetadataIndex", "SummaryOffset", "DataEnd"};
  return kNames[r.index()];
}

StreamReader::StreamReader(const std::filesystem::path& path) : path_(path), name_(path.string()) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw BagError(name_, "", "cannot read the file: " + ec.message());
  size_ = size;
  in_.open(path, std::ios::binary);
  if (!in_) throw BagError(name_, "", "cannot open the file");
  std::array<std::uint8_t, 8> magic{};
  if (size_ < magic.size()) fail(0, "too short for an MCAP file (" + std::to_string(size_) + " bytes)");
  read_exact(magic.data(), magic.size(), 0, "magic");
  if (std::memcmp(magic.data(), kMagic.data(), 5) != 0)
    fail(0, "not an MCAP file (expected the magic bytes 0x89 'MCAP')");
  if (magic[5] != kMagic[5])
    fail(5, "MCAP major version '" + std::string(1, static_cast<char>(magic[5])) +
                "' is not supported (expected '0')");
  if (magic[6] != '\r' || magic[7] != '\n') fail(6, "damaged magic bytes (expected \\r\\n after 'MCAP0')");
  data_crc_ = crc32(magic);
  pos_ = magic.size();
}

void StreamReader::fail(std::uint64_t offset, const std::string& reason) const {
  throw BagError(name_, "byte " + std::to_string(offset), reason);
}

void StreamReader::read_exact(void* out, std::uint64_t n, std::uint64_t offset, const char* what) {
  in_.seekg(static_cast<std::streamoff>(offset));
  in_.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
  if (!in_ || static_cast<std::uint64_t>(in_.gcount()) != n)
    fail(offset, std::string("cannot read the ") + what + " (" + std::to_string(n) + " bytes)");
}

std::optional<Record> StreamReader::next() {
  while (true) {
    if (chunk_pos_ < chunk_.size()) {
      if (auto r = next_in_chunk()) return r;
      continue;
    }
    if (finished_) return std::nullopt;
    if (seen_footer_) {
      std::array<std::uint8_t, 8> magic{};
      if (size_ - pos_ < magic.size()) fail(pos_, "the file ends without the trailing magic bytes");
      read_exact(magic.data(), magic.size(), pos_, "trailing magic");
      if (magic != kMagic) fail(pos_, "damaged trailing magic bytes (expected 0x89 'MCAP0' \\r\\n)");
      if (pos_ + magic.size() != size_)
        fail(pos_ + magic.size(), std::to_string(size_ - pos_ - magic.size()) +
                                      " bytes after the trailing magic (expected the end of the file)");
      finished_ = true;
      return std::nullopt;
    }
    const std::uint64_t offset = pos_;
    if (size_ - pos_ < kRecordHeaderBytes) fail(offset, "the file ends without a Footer record (truncated?)");
    std::array<std::uint8_t, kRecordHeaderBytes> head{};
    read_exact(head.data(), head.size(), offset, "record header");
    const std::uint8_t op = head[0];
    std::uint64_t length = 0;
    std::memcpy(&length, head.data() + 1, sizeof length);
    if (length > size_ - pos_ - kRecordHeaderBytes)
      fail(offset, std::string(opcode_name(op)) + " record of " + std::to_string(length) +
                       " bytes runs past the end of the file (" + std::to_string(size_) + " bytes)");
    Bytes content(static_cast<std::size_t>(length));
    if (length > 0) read_exact(content.data(), length, offset + kRecordHeaderBytes, "record");
    pos_ = offset + kRecordHeaderBytes + length;
    if (!seen_header_ && op != static_cast<std::uint8_t>(Opcode::header))
      fail(offset, std::string("the first record is a ") + opcode_name(op) + " (expected a Header)");
    if (!seen_data_end_ && op != static_cast<std::uint8_t>(Opcode::data_end)) {
      data_crc_ = crc32(head, data_crc_);
      data_crc_ = crc32(content, data_crc_);
    }
    if (!known(op)) continue;  // reserved for extensions: skipped
    switch (static_cast<Opcode>(op)) {
      case Opcode::header:
        if (seen_header_) fail(offset, "a second Header record");
        seen_header_ = true;
        break;
      case Opcode::footer: seen_footer_ = true; break;
      case Opcode::message_index: continue;  // an index of what the chunks return
      case Opcode::chunk: {
        read_chunk(content, chunk_, [&](const std::string& reason) { fail(offset, reason); });
        chunk_pos_ = 0;
        chunk_offset_ = offset;
        continue;
      }
      case Opcode::data_end: {
        Record rec = parse(op, content, offset, false);
        const auto& de = std::get<DataEnd>(rec);
        if (de.data_section_crc != 0 && de.data_section_crc != data_crc_)
          fail(offset, "DataEnd: CRC-32 of the data section does not match (the file is corrupt)");
        seen_data_end_ = true;
        return rec;
      }
      default: break;
    }
    return parse(op, content, offset, false);
  }
}

std::optional<Record> StreamReader::next_in_chunk() {
  const std::uint64_t at = chunk_pos_;
  auto where = [&](const std::string& reason) {
    fail(chunk_offset_, "Chunk, at byte " + std::to_string(at) + " of its records: " + reason);
  };
  if (chunk_.size() - chunk_pos_ < kRecordHeaderBytes) where("a record header is cut off");
  const std::uint8_t op = chunk_[chunk_pos_];
  std::uint64_t length = 0;
  std::memcpy(&length, chunk_.data() + chunk_pos_ + 1, sizeof length);
  if (length > chunk_.size() - chunk_pos_ - kRecordHeaderBytes)
    where(std::string(opcode_name(op)) + " record of " + std::to_string(length) + " bytes runs past the chunk");
  const auto begin = chunk_.begin() + static_cast<std::ptrdiff_t>(chunk_pos_ + kRecordHeaderBytes);
  Bytes content(begin, begin + static_cast<std::ptrdiff_t>(length));
  chunk_pos_ += kRecordHeaderBytes + static_cast<std::size_t>(length);
  if (chunk_pos_ == chunk_.size()) {
    chunk_.clear();
    chunk_pos_ = 0;
  }
  if (!known(op)) return std::nullopt;
  const auto o = static_cast<Opcode>(op);
  if (o != Opcode::schema && o != Opcode::channel && o != Opcode::message)
    where(std::string("a Chunk holds Schema, Channel and Message records, not ") + opcode_name(op));
  return parse(op, content, chunk_offset_, true);
}

Record StreamReader::parse(std::uint8_t op, const Bytes& content, std::uint64_t offset, bool in_chunk) {
  ByteReader r(content);
  const std::string prefix = std::string(in_chunk ? "in a Chunk: " : "") + opcode_name(op) + ": ";
  try {
    switch (static_cast<Opcode>(op)) {
      case Opcode::header: return read_header(r);
      case Opcode::footer: return read_footer(r);
      case Opcode::schema: {
        Schema s;
        s.id = r.u16("id");
        s.name = str(r, "name");
        s.encoding = str(r, "encoding");
        s.data = bytes_u32(r, "data");
        if (s.id == 0) fail(offset, prefix + "schema id 0 is reserved (no schema)");
        schema_defined_[s.id] = true;
        return s;
      }
      case Opcode::channel: {
        Channel c;
        c.id = r.u16("id");
        c.schema_id = r.u16("schema_id");
        c.topic = str(r, "topic");
        c.message_encoding = str(r, "message_encoding");
        c.metadata = string_map(r, "metadata");
        if (c.schema_id != 0 && !schema_defined_[c.schema_id])
          fail(offset, prefix + "channel " + std::to_string(c.id) + " (" + c.topic + ") uses schema " +
                           std::to_string(c.schema_id) + ", which no Schema record defined before it");
        channel_defined_[c.id] = true;
        return c;
      }
      case Opcode::message: {
        Message m;
        m.channel_id = r.u16("channel_id");
        m.sequence = r.u32("sequence");
        m.log_time = r.u64("log_time");
        m.publish_time = r.u64("publish_time");
        const auto rest = r.bytes(r.left(), "data");
        m.data.assign(rest.begin(), rest.end());
        if (!channel_defined_[m.channel_id])
          fail(offset, prefix + "message on channel " + std::to_string(m.channel_id) +
                           ", which no Channel record defined before it");
        return m;
      }
      case Opcode::chunk_index: return read_chunk_index(r);
      case Opcode::attachment: return read_attachment(r);
      case Opcode::attachment_index: return read_attachment_index(r);
      case Opcode::statistics: return read_statistics(r);
      case Opcode::metadata: return read_metadata(r);
      case Opcode::metadata_index: return read_metadata_index(r);
      case Opcode::summary_offset: return read_summary_offset(r);
      case Opcode::data_end: return read_data_end(r);
      case Opcode::chunk:
      case Opcode::message_index: break;
    }
  } catch (const ByteReader::Short& e) {
    fail(offset, prefix + e.what());
  }
  fail(offset, prefix + "not a record this reader returns");
}

std::vector<Record> read_records(const std::filesystem::path& path) {
  StreamReader reader(path);
  std::vector<Record> out;
  while (auto r = reader.next()) out.push_back(std::move(*r));
  return out;
}

}  // namespace odotune::bags::mcap

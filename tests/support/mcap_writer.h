// Test support (header-only): writes MCAP files, as the MCAP project lays
// out its conformance files; rebuilds a conformance file from its .json.
//
// Why: the conformance .mcap files in ../shared/data/mcap-conformance are Git
// LFS pointers (the MCAP repository stores them in LFS, and the copy we have
// holds only the pointers), while every .json is complete. The MCAP project
// generates each file deterministically from its records and the features
// in its name (foxglove/mcap, tests/conformance/scripts/generate-inputs.ts:
// ch chunked, mx message indexes, chx chunk index, pad three extra bytes
// 01 ff ff after each padded record's fields, rsh/rch schemas and channels
// repeated in the summary, st statistics, sum summary offsets, ax/mdx
// attachment and metadata indexes). This writer lays the records out the same
// way, written from the spec and that description (not from its code). The
// .json then checks the layout as well as the reader: chunk and summary
// offsets, lengths and the CRC-32s of chunk, data section and summary are in
// it, so a file that reads back to its .json has the reference layout.
#pragma once

#include <cstdint>
#include <cstring>
#include <functional>
#include <set>
#include <span>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <odotune/bags/compression.h>
#include <odotune/bags/mcap.h>

namespace odotune::bags::mcap::testing {

namespace detail {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

struct Buf {
  std::vector<std::uint8_t> b;
  std::size_t size() const { return b.size(); }
  template <class T>
  void put(T v) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    b.insert(b.end(), p, p + sizeof(T));
  }
  void str(const std::string& s) {
    put(static_cast<std::uint32_t>(s.size()));
    b.insert(b.end(), s.begin(), s.end());
  }
  void raw(const std::vector<std::uint8_t>& d) { b.insert(b.end(), d.begin(), d.end()); }
  void string_map(const StringMap& m) {
    Buf inner;
    for (const auto& [k, v] : m) {
      inner.str(k);
      inner.str(v);
    }
    put(static_cast<std::uint32_t>(inner.size()));
    raw(inner.b);
  }
  void u16_u64_map(const U16U64Map& m) {
    put(static_cast<std::uint32_t>(m.size() * 10));
    for (const auto& [k, v] : m) {
      put(k);
      put(v);
    }
  }
  // One record: opcode, length, fields, and the padding bytes when asked;
  // returns the record's whole size (opcode and length included).
  std::uint64_t record(Opcode op, bool pad, const std::function<void(Buf&)>& fields) {
    const std::size_t start = size();
    put(static_cast<std::uint8_t>(op));
    put(std::uint64_t{0});
    fields(*this);
    if (pad) {
      put(std::uint8_t{0x01});
      put(std::uint8_t{0xff});
      put(std::uint8_t{0xff});
    }
    const std::uint64_t length = size() - start - 9;
    std::memcpy(b.data() + start + 1, &length, sizeof length);
    return size() - start;
  }
};

inline void schema(Buf& out, const Schema& s, bool pad) {
  out.record(Opcode::schema, pad, [&](Buf& b) {
    b.put(s.id);
    b.str(s.name);
    b.str(s.encoding);
    b.put(static_cast<std::uint32_t>(s.data.size()));
    b.raw(s.data);
  });
}
inline void channel(Buf& out, const Channel& c, bool pad) {
  out.record(Opcode::channel, pad, [&](Buf& b) {
    b.put(c.id);
    b.put(c.schema_id);
    b.str(c.topic);
    b.str(c.message_encoding);
    b.string_map(c.metadata);
  });
}
inline void message(Buf& out, const Message& m) {  // never padded: its data runs to the end
  out.record(Opcode::message, false, [&](Buf& b) {
    b.put(m.channel_id);
    b.put(m.sequence);
    b.put(m.log_time);
    b.put(m.publish_time);
    b.raw(m.data);
  });
}

// Insertion-ordered map from channel id (the reference keeps JavaScript Maps).
template <class V>
struct OrderedMap {
  std::vector<std::pair<std::uint16_t, V>> items;
  V* find(std::uint16_t k) {
    for (auto& [key, v] : items)
      if (key == k) return &v;
    return nullptr;
  }
  V& at_or_add(std::uint16_t k) {
    if (V* v = find(k)) return *v;
    items.emplace_back(k, V{});
    return items.back().second;
  }
};

}  // namespace detail

// The feature suffixes of a conformance file name ("OneMessage-ch-mx-pad").
inline std::set<std::string> features_of(const std::string& stem) {
  std::set<std::string> f;
  std::stringstream ss(stem);
  std::string part;
  std::getline(ss, part, '-');  // the base name
  while (std::getline(ss, part, '-')) f.insert(part);
  return f;
}

// The file's bytes from its data records (Schema, Channel, Message,
// Attachment, Metadata, in order) and features (none: a plain unchunked file).
inline std::vector<std::uint8_t> conformance_file(const std::set<std::string>& features,
                                                  const std::vector<Record>& data_records) {
  using namespace detail;
  auto has = [&](const char* f) { return features.count(f) > 0; };
  const bool pad = has("pad"), chunked = has("ch"), message_index = has("mx");
  Buf out;
  out.raw(std::vector<std::uint8_t>(kMagic, kMagic + 8));
  out.record(Opcode::header, pad, [](Buf& b) {
    b.str("");
    b.str("");
  });

  Buf chunk;  // the chunk's records (never padded)
  OrderedMap<std::vector<std::pair<std::uint64_t, std::uint64_t>>> indexes;
  std::uint64_t chunk_messages = 0, chunk_start = 0, chunk_end = 0;
  std::uint64_t messages = 0;
  std::uint16_t schemas = 0;
  std::uint32_t channels = 0, attachments = 0, metadatas = 0;
  std::uint64_t start_time = 0, end_time = 0;
  OrderedMap<std::uint64_t> per_channel;
  std::vector<AttachmentIndex> attachment_indexes;
  std::vector<MetadataIndex> metadata_indexes;
  std::vector<ChunkIndex> chunk_indexes;

  for (const Record& rec : data_records) {
    if (const auto* s = std::get_if<Schema>(&rec)) {
      ++schemas;
      chunked ? schema(chunk, *s, false) : schema(out, *s, pad);
    } else if (const auto* c = std::get_if<Channel>(&rec)) {
      ++channels;
      if (chunked && message_index) indexes.at_or_add(c->id);
      chunked ? channel(chunk, *c, false) : channel(out, *c, pad);
    } else if (const auto* m = std::get_if<Message>(&rec)) {
      if (messages == 0 || m->log_time < start_time) start_time = m->log_time;
      if (messages == 0 || m->log_time > end_time) end_time = m->log_time;
      ++messages;
      ++per_channel.at_or_add(m->channel_id);
      if (chunked) {
        if (chunk_messages == 0 || m->log_time < chunk_start) chunk_start = m->log_time;
        if (chunk_messages == 0 || m->log_time > chunk_end) chunk_end = m->log_time;
        ++chunk_messages;
        if (message_index) indexes.at_or_add(m->channel_id).emplace_back(m->log_time, chunk.size());
        message(chunk, *m);
      } else {
        message(out, *m);
      }
    } else if (const auto* a = std::get_if<Attachment>(&rec)) {
      ++attachments;
      const std::uint64_t offset = out.size();
      const std::uint64_t length = out.record(Opcode::attachment, pad, [&](Buf& b) {
        const std::size_t from = b.size();
        b.put(a->log_time);
        b.put(a->create_time);
        b.str(a->name);
        b.str(a->media_type);
        b.put(static_cast<std::uint64_t>(a->data.size()));
        b.raw(a->data);
        b.put(crc32(std::span(b.b).subspan(from)));
      });
      if (has("ax"))
        attachment_indexes.push_back({offset, length, a->log_time, a->create_time, a->data.size(), a->name,
                                      a->media_type});
    } else if (const auto* md = std::get_if<Metadata>(&rec)) {
      ++metadatas;
      const std::uint64_t offset = out.size();
      const std::uint64_t length = out.record(Opcode::metadata, pad, [&](Buf& b) {
        b.str(md->name);
        b.string_map(md->metadata);
      });
      if (has("mdx")) metadata_indexes.push_back({offset, length, md->name});
    }
  }
  if (chunked) {
    const std::uint64_t start = out.size();
    const std::uint32_t crc = crc32(chunk.b);
    const std::uint64_t length = out.record(Opcode::chunk, false, [&](Buf& b) {
      b.put(chunk_start);
      b.put(chunk_end);
      b.put(static_cast<std::uint64_t>(chunk.size()));
      b.put(crc);
      b.str("");
      b.put(static_cast<std::uint64_t>(chunk.size()));
      b.raw(chunk.b);
    });
    U16U64Map offsets;
    std::uint64_t index_length = 0;
    for (const auto& [channel_id, entries] : indexes.items) {
      offsets.emplace_back(channel_id, out.size());
      index_length += out.record(Opcode::message_index, pad, [&](Buf& b) {
        b.put(channel_id);
        b.put(static_cast<std::uint32_t>(entries.size() * 16));
        for (const auto& [t, o] : entries) {
          b.put(t);
          b.put(o);
        }
      });
    }
    if (has("chx"))
      chunk_indexes.push_back({chunk_start, chunk_end, start, length, offsets, index_length, "", chunk.size(),
                               chunk.size()});
  }
  const std::uint32_t data_crc = crc32(out.b);
  out.record(Opcode::data_end, false, [&](Buf& b) { b.put(data_crc); });

  const std::uint64_t summary_start = out.size();
  auto group = [&](const std::function<void()>& write) {
    const std::uint64_t s = out.size();
    write();
    return std::pair<std::uint64_t, std::uint64_t>{s, out.size() - s};
  };
  const auto rsh = group([&] {
    if (has("rsh"))
      for (const Record& r : data_records)
        if (const auto* s = std::get_if<Schema>(&r)) schema(out, *s, pad);
  });
  const auto rch = group([&] {
    if (has("rch"))
      for (const Record& r : data_records)
        if (const auto* c = std::get_if<Channel>(&r)) channel(out, *c, pad);
  });
  const auto st = group([&] {
    if (!has("st")) return;
    out.record(Opcode::statistics, pad, [&](Buf& b) {
      b.put(messages);
      b.put(schemas);
      b.put(channels);
      b.put(attachments);
      b.put(metadatas);
      b.put(static_cast<std::uint32_t>(chunked ? 1 : 0));
      b.put(start_time);
      b.put(end_time);
      U16U64Map counts(per_channel.items.begin(), per_channel.items.end());
      b.u16_u64_map(counts);
    });
  });
  const auto mdx = group([&] {
    for (const auto& m : metadata_indexes)
      out.record(Opcode::metadata_index, pad, [&](Buf& b) {
        b.put(m.offset);
        b.put(m.length);
        b.str(m.name);
      });
  });
  const auto ax = group([&] {
    for (const auto& a : attachment_indexes)
      out.record(Opcode::attachment_index, pad, [&](Buf& b) {
        b.put(a.offset);
        b.put(a.length);
        b.put(a.log_time);
        b.put(a.create_time);
        b.put(a.data_size);
        b.str(a.name);
        b.str(a.media_type);
      });
  });
  const auto chx = group([&] {
    for (const auto& c : chunk_indexes)
      out.record(Opcode::chunk_index, pad, [&](Buf& b) {
        b.put(c.message_start_time);
        b.put(c.message_end_time);
        b.put(c.chunk_start_offset);
        b.put(c.chunk_length);
        b.u16_u64_map(c.message_index_offsets);
        b.put(c.message_index_length);
        b.str(c.compression);
        b.put(c.compressed_size);
        b.put(c.uncompressed_size);
      });
  });
  const bool has_summary = out.size() != summary_start;
  std::uint64_t summary_offset_start = 0;
  if (has("sum")) {
    summary_offset_start = out.size();
    const std::pair<Opcode, std::pair<std::uint64_t, std::uint64_t>> groups[] = {
        {Opcode::schema, rsh},         {Opcode::channel, rch},         {Opcode::statistics, st},
        {Opcode::metadata_index, mdx}, {Opcode::attachment_index, ax}, {Opcode::chunk_index, chx}};
    for (const auto& [op, g] : groups)
      if (g.second != 0)
        out.record(Opcode::summary_offset, pad, [&](Buf& b) {
          b.put(static_cast<std::uint8_t>(op));
          b.put(g.first);
          b.put(g.second);
        });
  }
  const std::uint64_t footer_summary_start = has_summary ? summary_start : 0;
  Buf footer_head;  // the footer's bytes up to its CRC, which the summary CRC covers
  footer_head.put(static_cast<std::uint8_t>(Opcode::footer));
  footer_head.put(std::uint64_t{20});
  footer_head.put(footer_summary_start);
  footer_head.put(summary_offset_start);
  std::uint32_t summary_crc = crc32(std::span(out.b).subspan(summary_start));
  summary_crc = crc32(footer_head.b, summary_crc);
  out.raw(footer_head.b);
  out.put(summary_crc);
  out.raw(std::vector<std::uint8_t>(kMagic, kMagic + 8));
  return out.b;
}

}  // namespace odotune::bags::mcap::testing

// Bounds-checked little-endian reads from a byte span, for the binary
// containers and message encodings of this module (MCAP, CDR, ROS 1).
//
// Contract: every read checks the bytes left first and throws
// ByteReader::Short (caught by the callers and turned into a BagError with
// file and position) instead of reading past the end; a declared length is
// compared with the bytes left before anything is allocated.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace odotune::bags {

static_assert(std::endian::native == std::endian::little,
              "bags/: the readers assume a little-endian host (x86-64, arm64)");

class ByteReader {
 public:
  // Thrown when a read would pass the end: what() names the field.
  struct Short : std::runtime_error {
    using std::runtime_error::runtime_error;
  };

  explicit ByteReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}

  std::size_t offset() const { return pos_; }
  std::size_t left() const { return bytes_.size() - pos_; }
  bool done() const { return pos_ == bytes_.size(); }

  template <class T>
  T read(const char* field) {
    need(sizeof(T), field);
    T v;
    std::memcpy(&v, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::uint8_t u8(const char* field) { return read<std::uint8_t>(field); }
  std::uint16_t u16(const char* field) { return read<std::uint16_t>(field); }
  std::uint32_t u32(const char* field) { return read<std::uint32_t>(field); }
  std::uint64_t u64(const char* field) { return read<std::uint64_t>(field); }

  // n bytes as a view into the input.
  std::span<const std::uint8_t> bytes(std::uint64_t n, const char* field) {
    need(n, field);
    auto s = bytes_.subspan(pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return s;
  }
  std::string_view text(std::uint64_t n, const char* field) {
    const auto b = bytes(n, field);
    return {reinterpret_cast<const char*>(b.data()), b.size()};
  }
  void skip(std::uint64_t n, const char* field) { bytes(n, field); }
  void seek(std::size_t offset) {
    if (offset > bytes_.size()) throw Short("seek past the end");
    pos_ = offset;
  }

 private:
  void need(std::uint64_t n, const char* field) const {
    if (n > left())
      throw Short(std::string(field) + ": needs " + std::to_string(n) + " bytes, " + std::to_string(left()) +
                  " left");
  }
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

}  // namespace odotune::bags

#include <odotune/bags/wire.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <stdexcept>

namespace odotune::bags {

WireReader::WireReader(std::span<const std::uint8_t> data, WireEncoding encoding)
    : r_(data), encoding_(encoding) {
  if (encoding_ == WireEncoding::cdr) {
    const std::uint8_t b0 = r_.u8("CDR encapsulation");
    const std::uint8_t b1 = r_.u8("CDR encapsulation");
    r_.u16("CDR encapsulation options");
    if (b0 != 0 || b1 > 1)
      throw std::runtime_error("CDR encapsulation " + std::to_string(b0) + " " + std::to_string(b1) +
                               " is not plain CDR (expected 00 01 or 00 00)");
    big_endian_ = b1 == 0;
    origin_ = r_.offset();
  }
}

void WireReader::align(std::size_t n) {
  if (encoding_ != WireEncoding::cdr) return;
  const std::size_t rel = r_.offset() - origin_;
  const std::size_t pad = (n - rel % n) % n;
  if (pad > 0) r_.skip(pad, "CDR alignment");
}

template <class T>
T WireReader::prim(const char* field) {
  align(sizeof(T));
  T v = r_.read<T>(field);
  if (big_endian_ && sizeof(T) > 1) {
    auto bytes = std::bit_cast<std::array<std::uint8_t, sizeof(T)>>(v);
    std::reverse(bytes.begin(), bytes.end());
    v = std::bit_cast<T>(bytes);
  }
  return v;
}

double WireReader::f64(const char* field) { return prim<double>(field); }
float WireReader::f32(const char* field) { return prim<float>(field); }
std::uint32_t WireReader::u32(const char* field) { return prim<std::uint32_t>(field); }
std::int32_t WireReader::i32(const char* field) { return prim<std::int32_t>(field); }
std::uint16_t WireReader::u16(const char* field) { return prim<std::uint16_t>(field); }
std::uint8_t WireReader::u8(const char* field) { return prim<std::uint8_t>(field); }
std::int8_t WireReader::i8(const char* field) { return prim<std::int8_t>(field); }

std::string WireReader::string(const char* field) {
  const std::uint32_t n = u32(field);
  std::string_view s = r_.text(n, field);
  if (encoding_ == WireEncoding::cdr) {
    if (n == 0) return {};  // some writers give 0 for an empty string
    if (s.back() != '\0') throw ByteReader::Short(std::string(field) + ": CDR string without its NUL");
    s.remove_suffix(1);
  }
  return std::string(s);
}

std::uint32_t WireReader::count(const char* field, std::size_t min_element_bytes) {
  const std::uint32_t n = u32(field);
  if (min_element_bytes > 0 && n > left() / min_element_bytes)
    throw ByteReader::Short(std::string(field) + ": " + std::to_string(n) + " elements cannot fit in the " +
                            std::to_string(left()) + " bytes left");
  return n;
}

std::int64_t WireReader::time_ns(const char* field) {
  if (encoding_ == WireEncoding::ros1) {
    const std::uint32_t sec = u32(field);
    const std::uint32_t nsec = u32(field);
    return static_cast<std::int64_t>(sec) * 1000000000LL + nsec;
  }
  const std::int32_t sec = i32(field);
  const std::uint32_t nsec = u32(field);
  return static_cast<std::int64_t>(sec) * 1000000000LL + nsec;
}

}  // namespace odotune::bags

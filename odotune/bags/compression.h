// Decompression of bag chunks with Debian's libraries: zstd (libzstd) and the
// lz4 frame format (liblz4), as MCAP chunks use them; CRC-32 (zlib's, the
// IEEE polynomial MCAP specifies).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace odotune::bags {

// Decompresses `in` ("zstd" or "lz4"; "" copies) into exactly
// `uncompressed_size` bytes. Throws std::runtime_error with the reason
// (corrupt data, a size other than declared, an unknown compression).
std::vector<std::uint8_t> decompress(std::string_view compression, std::span<const std::uint8_t> in,
                                     std::uint64_t uncompressed_size);

// CRC-32 (IEEE 802.3; zlib's crc32) of `data`, continuing from `crc`.
std::uint32_t crc32(std::span<const std::uint8_t> data, std::uint32_t crc = 0);

}  // namespace odotune::bags

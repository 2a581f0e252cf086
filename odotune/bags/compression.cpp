#include <odotune/bags/compression.h>

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <limits>
#include <stdexcept>

namespace odotune::bags {

std::vector<std::uint8_t> decompress(std::string_view compression, std::span<const std::uint8_t> in,
                                     std::uint64_t uncompressed_size) {
  if (uncompressed_size > std::numeric_limits<std::size_t>::max())
    throw std::runtime_error("uncompressed size too large");
  std::vector<std::uint8_t> out(static_cast<std::size_t>(uncompressed_size));
  if (compression.empty()) {
    if (in.size() != uncompressed_size)
      throw std::runtime_error("uncompressed chunk of " + std::to_string(in.size()) + " bytes, declared " +
                               std::to_string(uncompressed_size));
    std::copy(in.begin(), in.end(), out.begin());
    return out;
  }
  if (compression == "zstd") {
    const std::size_t n = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
    if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
    if (n != out.size())
      throw std::runtime_error("zstd chunk gives " + std::to_string(n) + " bytes, declared " +
                               std::to_string(uncompressed_size));
    return out;
  }
  if (compression == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
      throw std::runtime_error("lz4: cannot create a decompression context");
    std::size_t done_in = 0, done_out = 0;
    std::size_t hint = 1;
    while (hint != 0 && done_in < in.size()) {
      std::size_t n_in = in.size() - done_in;
      std::size_t n_out = out.size() - done_out;
      hint = LZ4F_decompress(ctx, out.data() + done_out, &n_out, in.data() + done_in, &n_in, nullptr);
      if (LZ4F_isError(hint)) {
        const std::string why = LZ4F_getErrorName(hint);
        LZ4F_freeDecompressionContext(ctx);
        throw std::runtime_error("lz4: " + why);
      }
      done_in += n_in;
      done_out += n_out;
      if (n_in == 0 && n_out == 0) break;  // no progress: truncated frame
    }
    LZ4F_freeDecompressionContext(ctx);
    if (hint != 0) throw std::runtime_error("lz4: truncated frame");
    if (done_out != out.size())
      throw std::runtime_error("lz4 chunk gives " + std::to_string(done_out) + " bytes, declared " +
                               std::to_string(uncompressed_size));
    return out;
  }
  throw std::runtime_error("unknown compression '" + std::string(compression) +
                           "' (expected none, zstd or lz4)");
}

std::uint32_t crc32(std::span<const std::uint8_t> data, std::uint32_t crc) {
  // zlib's length type is uInt: feed large spans in pieces.
  std::size_t done = 0;
  uLong c = crc;
  while (done < data.size()) {
    const std::size_t n = std::min<std::size_t>(data.size() - done, 1u << 30);
    c = ::crc32(c, data.data() + done, static_cast<uInt>(n));
    done += n;
  }
  return static_cast<std::uint32_t>(c);
}

}  // namespace odotune::bags

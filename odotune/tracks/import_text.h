// Line-oriented reading of text files, shared by the dataset importers
// (importers.h); trim() and quote() also serve the track reader. Not a track parser: it only knows lines, fields and
// numbers, and turns every problem into a TrackError(file, line, reason).
//
// Contract: a LineReader never allocates more than kMaxLineBytes per line, so
// it is safe on any input (binary garbage, one endless line, a directory).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace odotune::tracks::import_text {

inline constexpr std::size_t kMaxLineBytes = std::size_t{64} * 1024;

// True when path names an existing regular file (no exception).
bool is_file(const std::filesystem::path& path);

class LineReader {
 public:
  // Opens `path`. `what` describes the expected file in the error message,
  // e.g. "MRCLAM odometry file RobotN_Odometry.dat". Throws TrackError(path,
  // 0, ...) when the file is missing, is not a regular file or cannot be read.
  LineReader(const std::filesystem::path& path, std::string_view what);

  // Reads the next line into `line` (without "\n" or "\r\n"; a UTF-8 BOM at
  // the start of the file is dropped). Returns false at the end of the file.
  // Throws TrackError on a read error, a NUL byte or a line longer than
  // kMaxLineBytes. `line` stays valid until the next call.
  bool next(std::string_view& line);

  // 1-based number of the line last returned (0 before the first).
  std::size_t line_no() const { return line_no_; }
  const std::string& file() const { return file_; }

  // Throws TrackError(file(), line_no(), reason).
  [[noreturn]] void fail(const std::string& reason) const;

 private:
  std::string file_;
  std::ifstream in_;
  std::string buf_;
  std::size_t line_no_ = 0;
};

// Removes leading and trailing spaces and tabs.
std::string_view trim(std::string_view s);
// Splits on commas; each field is trimmed. "a,,b," gives {a, "", b, ""}.
std::vector<std::string_view> split_csv(std::string_view line);
// Splits on runs of spaces/tabs; no empty fields.
std::vector<std::string_view> split_ws(std::string_view line);

// A finite decimal number ("1.5", "-2e-3", "+4"); nullopt for anything else
// (including nan, inf and trailing garbage).
std::optional<double> to_double(std::string_view s);
// A whole number in int64 range ("-12", "+7"); nullopt otherwise.
std::optional<std::int64_t> to_int64(std::string_view s);

// Fixed-point decimal "[-]SSSS[.FFFFFFFFF]" (at most 9 fraction digits, no
// exponent) as integer nanoseconds, exactly: the way to subtract two Unix
// epoch stamps (~1.2e9 s) without losing their milliseconds to double
// rounding. nullopt for anything else or on int64 overflow.
std::optional<std::int64_t> decimal_to_ns(std::string_view s);
// The inverse, with trailing fraction zeros removed: 1248446182116000000 ->
// "1248446182.116".
std::string ns_to_decimal(std::int64_t ns);

// `s` for an error message: in single quotes, at most 40 bytes, control,
// quote and non-ASCII bytes as \xHH, so that the message stays one line.
std::string quote(std::string_view s);

// Shortest decimal that reads back to the same double ("0.042", "2796.8").
std::string fmt_double(double v);

}  // namespace odotune::tracks::import_text

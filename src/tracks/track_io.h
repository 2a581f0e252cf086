// Reading and writing track files (../shared/specs/track-format.md).
//
// Reader contract: every error rule of the spec is reported as a TrackError
// naming the file, the 1-based line and the reason (and what was expected);
// the reader never crashes, hangs or allocates without bound on any input.
// Writer contract: what write_track writes, read_track reads back to the same
// numbers bit for bit; the file appears atomically (written to a temporary
// beside it, then renamed), so a failure never leaves a partial file.
#pragma once

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <string_view>

#include "tracks/track.h"

namespace odotune {

class TrackError : public std::runtime_error {
 public:
  // what() is "FILE:LINE: REASON" (or "FILE: REASON" when line is 0).
  TrackError(std::string file, std::size_t line, std::string reason);
  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string file_;
  std::size_t line_;
  std::string reason_;
};

// Reads a track file. Throws TrackError.
Track read_track(const std::filesystem::path& path);
// Parses a track from a stream; `filename` is used in error messages and as
// the default name (its stem). Throws TrackError.
Track parse_track(std::istream& in, std::string_view filename);

// Writes a track in odotune-track/1 form. Throws std::runtime_error naming the
// path on an I/O failure.
void write_track(const Track& track, const std::filesystem::path& path);
// The same text, to a stream (no atomicity).
void format_track(const Track& track, std::ostream& out);

}  // namespace odotune

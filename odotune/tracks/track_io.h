// Reading and writing track files (../shared/specs/track-format.md).
//
// Reader contract: every error rule of the spec is reported as a TrackError
// naming the file, the 1-based line and the reason (and what was expected);
// the reader never crashes, hangs or allocates without bound on any input.
// Writer contract: what write_track writes, read_track reads back to the same
// numbers bit for bit; the file appears atomically (written to a temporary
// beside it, then renamed), so a failure never leaves a partial file.
//
// Reader policies where the spec leaves a choice (implemented in track_reader.cpp):
//  - A UTF-8 BOM and CRLF line endings are accepted. Cells and header names
//    are trimmed of spaces/tabs; numbers are parsed with std::from_chars
//    (locale-independent; a leading '+' and exponents like 1e-3 accepted).
//  - Limits: a line may hold at most 1 MiB, a header at most 256 columns.
//  - A header with no data row after it is rejected (a Track cannot hold a
//    column that is present but has no rows). A file without header is too.
//  - A known metadata key (format, name, origin, robot.*) given twice is an
//    error; unknown keys are kept in TrackMeta::extra in file order, never an
//    error. `# text` lines without ':' before the header are comments.
//    origin is kept verbatim; robot.* values must be finite and positive.
//  - Unknown columns are ignored unless they look like a misspelling of a
//    known name that the header lacks: equal ignoring case; an edit
//    (Damerau) distance of at most 2 (1 for names of <= 5 chars, 0 for "t");
//    a known name followed by a separator and more ("t[s]", "gyro_z_rad"),
//    a known name of >= 4 chars followed by anything ("ticks_left") or
//    preceded by text and a separator ("raw_gyro_z"); or a known name cut at
//    an underscore ("gyro"). The error then names the probable column.
//  - A tick cell must be a decimal signed 64-bit integer other than INT64_MIN
//    (which is kNoTick, "no sample").
// Writer: format_track throws std::invalid_argument (before writing anything)
// for a track the reader would reject or misread (no rows, no odometry,
// missing robot.* for wheel columns, infinite values, metadata keys with ':',
// line breaks or colliding with a standard key); write_track reports that and
// I/O failures as std::runtime_error naming the path. Metadata values are
// written verbatim, so surrounding blanks in them do not survive a re-read.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/tracks/track.h>

namespace odotune::tracks {

// The metadata keys track-format.md defines, and odotune's
// source.body_velocity (docs/track-format.md): TrackMeta's own fields; every
// other key is kept verbatim in TrackMeta::extra. Read and write share it.
inline constexpr std::array<std::string_view, 8> kStandardMetaKeys = {"format",
                                                                      "name",
                                                                      "origin",
                                                                      "robot.ticks_per_rev",
                                                                      "robot.wheel_radius_left",
                                                                      "robot.wheel_radius_right",
                                                                      "robot.wheel_base",
                                                                      "source.body_velocity"};

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
// Reads several track files, for the commands and jobs: a bad file becomes
// one core::Failure line (file:line: reason) instead of a TrackError.
std::vector<Track> load_tracks(const std::vector<std::string>& paths);
// Parses a track from a stream; `filename` is used in error messages and as
// the default name (its stem). Throws TrackError.
Track parse_track(std::istream& in, std::string_view filename);

// Writes a track in odotune-track/1 form. Throws std::runtime_error naming the
// path on an I/O failure.
void write_track(const Track& track, const std::filesystem::path& path);
// The same text, to a stream (no atomicity). Throws std::invalid_argument for
// an unwritable track, std::runtime_error if the stream fails.
void format_track(const Track& track, std::ostream& out);

}  // namespace odotune::tracks

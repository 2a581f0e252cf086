// Writer of odotune-track/1 files (../shared/specs/track-format.md).
//
// Layout written: the format line; name and origin (each if non-empty); the
// robot.* keys that are set; source.body_velocity if set; the extra keys in order; the header (t, ticks_l,
// ticks_r if present, then the present real columns in Col order); one row per
// sample. Numbers are the shortest decimal that reads back to the same double
// (fmt "{}"), so write -> read is bit-identical; NaN and kNoTick are empty cells.
// Before writing anything the track is checked against the reader's rules, so
// the writer never produces a file that read_track would reject.
#include <array>
#include <cerrno>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/tracks/track_io.h>

namespace odotune::tracks {

namespace {

bool has_line_break(std::string_view s) { return s.find_first_of("\r\n") != std::string_view::npos; }

// Throws std::invalid_argument naming the first thing read_track would reject
// (or misread) in what format_track would write for `track`.
void check_writable(const Track& track) {
  const auto bad = [](const std::string& why) { throw std::invalid_argument(why); };
  const TrackMeta& m = track.meta();
  if (has_line_break(m.name)) bad("track name contains a line break");
  if (has_line_break(m.origin)) bad("track origin contains a line break");
  for (const auto& [key, value] : m.extra) {
    const bool blank_edge = key.empty() || key.front() == ' ' || key.front() == '\t' || key.back() == ' ' ||
                            key.back() == '\t';
    if (blank_edge || key.find(':') != std::string::npos || has_line_break(key))
      bad(fmt::format("metadata key '{}' cannot be written (empty, ':', line break or surrounding blanks)",
                      key));
    for (std::string_view k : kStandardMetaKeys)
      if (key == k) bad(fmt::format("extra metadata key '{}' collides with a standard key", key));
    if (has_line_break(value)) bad(fmt::format("value of metadata key '{}' contains a line break", key));
  }
  const auto positive = [&](const std::optional<double>& v, std::string_view key) {
    if (v && !(std::isfinite(*v) && *v > 0)) bad(fmt::format("{} must be finite and positive, is {}", key, *v));
  };
  positive(m.ticks_per_rev, "robot.ticks_per_rev");
  positive(m.wheel_radius_left_m, "robot.wheel_radius_left");
  positive(m.wheel_radius_right_m, "robot.wheel_radius_right");
  positive(m.wheel_base_m, "robot.wheel_base");

  if (track.size() == 0) bad("track has no rows");
  if (!track.has_odometry()) bad("track has no odometry source (ticks, omega or v_cmd/w_cmd pair)");
  const bool ticks = !track.ticks_l().empty() || !track.ticks_r().empty();
  if (ticks && !m.ticks_per_rev) bad("track has tick columns but no robot.ticks_per_rev");
  if ((ticks || track.has(Col::omega_l) || track.has(Col::omega_r)) &&
      !(m.wheel_radius_left_m && m.wheel_radius_right_m && m.wheel_base_m))
    bad("track has wheel columns but not all of robot.wheel_radius_left/right and robot.wheel_base");
  for (double t : track.t())
    if (!std::isfinite(t)) bad(fmt::format("t holds a non-finite value {}", t));
  for (int c = 0; c < kNumCols; ++c)
    for (double v : track.col(static_cast<Col>(c)))
      if (std::isinf(v))
        bad(fmt::format("column {} holds an infinite value", column_name(static_cast<Col>(c))));
}

}  // namespace

void format_track(const Track& track, std::ostream& out) {
  check_writable(track);
  const TrackMeta& m = track.meta();
  fmt::memory_buffer buf;
  auto it = std::back_inserter(buf);
  fmt::format_to(it, "# format: odotune-track/1\n");
  if (!m.name.empty()) fmt::format_to(it, "# name: {}\n", m.name);
  if (!m.origin.empty()) fmt::format_to(it, "# origin: {}\n", m.origin);
  if (m.ticks_per_rev) fmt::format_to(it, "# robot.ticks_per_rev: {}\n", *m.ticks_per_rev);
  if (m.wheel_radius_left_m) fmt::format_to(it, "# robot.wheel_radius_left: {}\n", *m.wheel_radius_left_m);
  if (m.wheel_radius_right_m) fmt::format_to(it, "# robot.wheel_radius_right: {}\n", *m.wheel_radius_right_m);
  if (m.wheel_base_m) fmt::format_to(it, "# robot.wheel_base: {}\n", *m.wheel_base_m);
  if (m.body_velocity) fmt::format_to(it, "# source.body_velocity: {}\n", to_string(*m.body_velocity));
  for (const auto& [key, value] : m.extra) fmt::format_to(it, "# {}: {}\n", key, value);

  const auto& tl = track.ticks_l();
  const auto& tr = track.ticks_r();
  fmt::format_to(it, "t");
  if (!tl.empty()) fmt::format_to(it, ",ticks_l");
  if (!tr.empty()) fmt::format_to(it, ",ticks_r");
  std::vector<const std::vector<double>*> cols;
  for (int c = 0; c < kNumCols; ++c)
    if (track.has(static_cast<Col>(c))) {
      fmt::format_to(it, ",{}", column_name(static_cast<Col>(c)));
      cols.push_back(&track.col(static_cast<Col>(c)));
    }
  buf.push_back('\n');

  const auto flush = [&] {
    out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    buf.clear();
    if (!out) throw std::runtime_error("error writing the track to the stream");
  };
  const auto& t = track.t();
  for (std::size_t i = 0; i < t.size(); ++i) {
    fmt::format_to(it, "{}", t[i]);
    for (const auto* ticks : {&tl, &tr}) {
      if (ticks->empty()) continue;
      buf.push_back(',');
      if ((*ticks)[i] != kNoTick) fmt::format_to(it, "{}", (*ticks)[i]);
    }
    for (const auto* col : cols) {
      buf.push_back(',');
      if (!std::isnan((*col)[i])) fmt::format_to(it, "{}", (*col)[i]);
    }
    buf.push_back('\n');
    if (buf.size() >= std::size_t{64} * 1024) flush();
  }
  flush();
}

void write_track(const Track& track, const std::filesystem::path& path) {
  core::write_atomically(path, "track", [&track](std::ostream& out) { format_track(track, out); });
}

}  // namespace odotune::tracks

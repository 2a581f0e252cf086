// Reader of odotune-track/1 files (../shared/specs/track-format.md).
//
// Limits (so that no input can make the reader allocate without bound): a
// line may hold at most kMaxLineBytes bytes and a header at most kMaxColumns
// columns; lines are read through a fixed-size chunk buffer, never whole.
// Policy choices beyond the spec (documented in track_io.h):
//  - a header without any data row is rejected (a Track cannot represent a
//    column that is present but has no rows);
//  - a known metadata key given twice is rejected; unknown keys never fail;
//  - a tick cell equal to INT64_MIN is rejected (it is kNoTick, "no sample").
#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/tracks/import_text.h>
#include <odotune/tracks/track_io.h>

namespace odotune::tracks {

TrackError::TrackError(std::string file, std::size_t line, std::string reason)
    : std::runtime_error(line == 0 ? fmt::format("{}: {}", file, reason)
                                   : fmt::format("{}:{}: {}", file, line, reason)),
      file_(std::move(file)),
      line_(line),
      reason_(std::move(reason)) {}

namespace {

using import_text::quote;
using import_text::trim;

enum class NumParse { kOk, kBad, kNonFinite, kOutOfRange };

// Parses a whole cell (surrounding blanks and one leading '+' allowed) with
// std::from_chars, so the result does not depend on the locale.
NumParse parse_real(std::string_view text, double& out) {
  std::string_view s = trim(text);
  if (s.size() > 1 && s[0] == '+' && s[1] != '+' && s[1] != '-') s.remove_prefix(1);
  if (s.empty()) return NumParse::kBad;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  if (ec == std::errc::result_out_of_range && ptr == s.data() + s.size()) return NumParse::kOutOfRange;
  if (ec != std::errc() || ptr != s.data() + s.size()) return NumParse::kBad;
  return std::isfinite(out) ? NumParse::kOk : NumParse::kNonFinite;
}

NumParse parse_int64(std::string_view text, std::int64_t& out) {
  std::string_view s = trim(text);
  if (s.size() > 1 && s[0] == '+' && s[1] != '+' && s[1] != '-') s.remove_prefix(1);
  if (s.empty()) return NumParse::kBad;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out, 10);
  if (ec == std::errc::result_out_of_range && ptr == s.data() + s.size()) return NumParse::kOutOfRange;
  if (ec != std::errc() || ptr != s.data() + s.size()) return NumParse::kBad;
  return NumParse::kOk;
}

char lower(char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; }
bool is_alnum(char c) { return (c >= '0' && c <= '9') || (lower(c) >= 'a' && lower(c) <= 'z'); }

bool iequal(std::string_view a, std::string_view b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) { return lower(x) == lower(y); });
}
bool istarts_with(std::string_view s, std::string_view p) {
  return s.size() >= p.size() && iequal(s.substr(0, p.size()), p);
}
bool iends_with(std::string_view s, std::string_view p) {
  return s.size() >= p.size() && iequal(s.substr(s.size() - p.size()), p);
}

// Case-insensitive optimal-string-alignment (restricted Damerau-Levenshtein)
// distance; only called with short strings (both at most ~12 bytes).
std::size_t osa_distance(std::string_view a, std::string_view b) {
  constexpr std::size_t kMax = 16;
  std::array<std::array<std::size_t, kMax + 1>, kMax + 1> d{};
  const std::size_t n = std::min(a.size(), kMax), m = std::min(b.size(), kMax);
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i)
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[n][m];
}

// How much `name` looks like a misspelling of the known column `known`
// (lower is closer), or nullopt if it does not.
std::optional<std::size_t> misspelling_score(std::string_view name, std::string_view known) {
  if (iequal(name, known)) return 0;
  // Edit distance, with a budget that shrinks for short names so that common
  // unrelated columns ("x", "dt", "acc_x") are not taken for "t" or "aps_x".
  const std::size_t budget = known.size() <= 2 ? 0 : known.size() <= 5 ? 1 : 2;
  const std::size_t len_gap = name.size() > known.size() ? name.size() - known.size()
                                                         : known.size() - name.size();
  if (len_gap <= budget) {
    const std::size_t d = osa_distance(name, known);
    if (d <= budget) return d;
  }
  // A known name with something added: "gyro_z_rad", "t[s]", "ticks_left", "raw_gyro_z".
  if (istarts_with(name, known) && (known.size() >= 4 || !is_alnum(name[known.size()]))) return 3;
  if (known.size() >= 4 && iends_with(name, known) && !is_alnum(name[name.size() - known.size() - 1])) return 3;
  // A known name cut at an underscore: "gyro" for "gyro_z", "ticks" for "ticks_l".
  if (!name.empty() && known.size() > name.size() && istarts_with(known, name) && known[name.size()] == '_')
    return 4;
  return std::nullopt;
}

// The known column that `name` most likely misspells, among those not already
// in the header (`present`): a header with gyro_z may also carry gyro_x.
std::optional<std::string_view> suggest_column(std::string_view name,
                                               const std::vector<std::string_view>& present) {
  std::optional<std::string_view> best;
  std::size_t best_score = 0;
  for (std::string_view known : known_column_names()) {
    if (std::find(present.begin(), present.end(), known) != present.end()) continue;
    const auto score = misspelling_score(name, known);
    if (score && (!best || *score < best_score)) {
      best = known;
      best_score = *score;
    }
  }
  return best;
}

constexpr std::string_view kFormatValue = "odotune-track/1";
constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;  // 1 MiB
constexpr std::size_t kMaxColumns = 256;

// Splits a stream into lines ('\n'; a trailing '\r' is dropped) through a
// fixed chunk buffer, refusing lines longer than kMaxLineBytes.
class LineReader {
 public:
  enum class Status { kLine, kEof, kTooLong };
  explicit LineReader(std::istream& in) : sb_(in.rdbuf()), buf_(std::size_t{64} * 1024) {}

  Status next(std::string& line) {
    line.clear();
    bool any = false;
    for (;;) {
      if (pos_ == end_) {
        if (sb_ == nullptr || eof_) break;
        end_ = static_cast<std::size_t>(sb_->sgetn(buf_.data(), static_cast<std::streamsize>(buf_.size())));
        pos_ = 0;
        if (end_ == 0) {
          eof_ = true;
          break;
        }
      }
      any = true;
      const char* s = buf_.data() + pos_;
      const auto* nl = static_cast<const char*>(std::memchr(s, '\n', end_ - pos_));
      const std::size_t n = nl != nullptr ? static_cast<std::size_t>(nl - s) : end_ - pos_;
      if (line.size() + n > kMaxLineBytes) return Status::kTooLong;
      line.append(s, n);
      pos_ += n + (nl != nullptr ? 1 : 0);
      if (nl != nullptr) break;
    }
    if (!any) return Status::kEof;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return Status::kLine;
  }

 private:
  std::streambuf* sb_;
  std::vector<char> buf_;
  std::size_t pos_ = 0, end_ = 0;
  bool eof_ = false;
};

enum class Kind { kIgnored, kTime, kTickL, kTickR, kReal };
struct Column {
  std::string name;
  Kind kind = Kind::kIgnored;
  Col col = Col::kCount;
};

bool is_blank(std::string_view s) { return trim(s).empty(); }
bool is_hash_line(std::string_view s) {
  const auto t = trim(s);
  return !t.empty() && t.front() == '#';
}

class Parser {
 public:
  Parser(std::istream& in, std::string_view filename) : reader_(in), file_(filename) {}

  Track run() {
    read_format_line();
    read_metadata_and_header();
    read_rows();
    if (data_.meta.name.empty()) data_.meta.name = std::filesystem::path(file_).stem().string();
    try {
      return Track(std::move(data_));
    } catch (const std::invalid_argument& e) {  // not expected: the rows were checked
      throw TrackError(file_, 0, e.what());
    }
  }

 private:
  [[noreturn]] void fail(std::string reason) const { throw TrackError(file_, line_no_, std::move(reason)); }

  bool next_line() {
    ++line_no_;
    switch (reader_.next(line_)) {
      case LineReader::Status::kLine: return true;
      case LineReader::Status::kEof: --line_no_; return false;
      case LineReader::Status::kTooLong:
        fail(fmt::format("line longer than {} bytes; expected short CSV lines", kMaxLineBytes));
    }
    return false;
  }

  // "# key: value" -> (key, value), both trimmed; nullopt for a plain comment.
  static std::optional<std::pair<std::string_view, std::string_view>> split_meta(std::string_view line) {
    std::string_view s = trim(line);
    s.remove_prefix(1);  // '#'
    const auto colon = s.find(':');
    if (colon == std::string_view::npos) return std::nullopt;
    const auto key = trim(s.substr(0, colon));
    if (key.empty()) return std::nullopt;
    return std::pair{key, trim(s.substr(colon + 1))};
  }

  void read_format_line() {
    const std::string expected = fmt::format("expected '# format: {}'", kFormatValue);
    if (!next_line()) {
      line_no_ = 1;
      fail(fmt::format("missing format line, {} (the file is empty)", expected));
    }
    std::string_view s = line_;
    if (s.substr(0, 3) == "\xEF\xBB\xBF") s.remove_prefix(3);  // UTF-8 BOM
    const auto kv = is_hash_line(s) ? split_meta(s) : std::nullopt;
    if (!kv || kv->first != "format") fail(fmt::format("missing format line, {}", expected));
    if (kv->second != kFormatValue) fail(fmt::format("unknown format {}, {}", quote(kv->second), expected));
    seen_keys_.emplace_back("format", line_no_);
  }

  void set_robot(std::optional<double>& field, std::string_view key, std::string_view value,
                 std::string_view unit) {
    double v = 0;
    if (parse_real(value, v) != NumParse::kOk || !(v > 0))
      fail(fmt::format("metadata {} must be a finite positive number{}, got {}", key, unit, quote(value)));
    field = v;
  }

  void read_meta(std::string_view key, std::string_view value) {
    if (std::find(kStandardMetaKeys.begin(), kStandardMetaKeys.end(), key) == kStandardMetaKeys.end()) {
      data_.meta.extra.emplace_back(std::string(key), std::string(value));
      return;
    }
    for (const auto& [k, at] : seen_keys_)
      if (k == key)
        fail(fmt::format("duplicate metadata key '{}' (first given on line {}); expected it once", key, at));
    seen_keys_.emplace_back(std::string(key), line_no_);
    TrackMeta& m = data_.meta;
    if (key == "name")
      m.name = value;
    else if (key == "origin")
      m.origin = value;
    else if (key == "robot.ticks_per_rev")
      set_robot(m.ticks_per_rev, key, value, " (counts per revolution)");
    else if (key == "robot.wheel_radius_left")
      set_robot(m.wheel_radius_left_m, key, value, " [m]");
    else if (key == "robot.wheel_radius_right")
      set_robot(m.wheel_radius_right_m, key, value, " [m]");
    else if (key == "robot.wheel_base")
      set_robot(m.wheel_base_m, key, value, " [m]");
    else if (key == "source.body_velocity") {
      BodyVelocitySource b{};
      if (!parse_body_velocity_source(value, &b))
        fail(fmt::format("metadata source.body_velocity is {}, expected 'commanded' or 'measured' (what v_cmd, "
                         "w_cmd are)",
                         quote(value)));
      m.body_velocity = b;
    }
  }

  void read_metadata_and_header() {
    while (next_line()) {
      if (is_blank(line_)) continue;
      if (is_hash_line(line_)) {
        if (const auto kv = split_meta(line_)) read_meta(kv->first, kv->second);
        continue;
      }
      header_line_ = line_no_;
      parse_header(line_);
      return;
    }
    line_no_ = std::max<std::size_t>(line_no_, 1);
    fail("no header line; expected a line of column names (e.g. 't,ticks_l,ticks_r') after the metadata");
  }

  void parse_header(std::string_view line) {
    const std::size_t n = static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
    if (n > kMaxColumns) fail(fmt::format("header has {} columns; at most {} are supported", n, kMaxColumns));
    const auto& known = known_column_names();
    std::vector<std::string_view> present;
    std::size_t start = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t comma = std::min(line.find(',', start), line.size());
      const std::string_view name = trim(line.substr(start, comma - start));
      start = comma + 1;
      if (name.empty())
        fail(fmt::format(
            "empty column name at position {} of the header; expected a name such as 't' or 'gyro_z'", i + 1));
      for (std::size_t j = 0; j < cols_.size(); ++j)
        if (cols_[j].name == name)
          fail(fmt::format("duplicate column {} (positions {} and {}); expected each column once", quote(name),
                           j + 1, i + 1));
      Column c{std::string(name), Kind::kIgnored, Col::kCount};
      if (name == "t")
        c.kind = Kind::kTime;
      else if (name == "ticks_l")
        c.kind = Kind::kTickL;
      else if (name == "ticks_r")
        c.kind = Kind::kTickR;
      for (int k = 0; k < kNumCols; ++k)
        if (name == column_name(static_cast<Col>(k))) {
          c.kind = Kind::kReal;
          c.col = static_cast<Col>(k);
        }
      if (std::find(known.begin(), known.end(), name) != known.end()) present.push_back(name);
      cols_.push_back(std::move(c));
    }
    for (const Column& c : cols_)
      if (c.kind == Kind::kIgnored)
        if (const auto guess = suggest_column(c.name, present))
          fail(fmt::format("unknown column {}; did you mean '{}'?", quote(c.name), *guess));
    check_header(present);
  }

  void check_header(const std::vector<std::string_view>& present) {
    const auto has = [&](std::string_view n) {
      return std::find(present.begin(), present.end(), n) != present.end();
    };
    if (!has("t")) fail("missing column 't' (time [s]); expected it in the header");
    if (!(has("ticks_l") && has("ticks_r")) && !(has("omega_l") && has("omega_r")) &&
        !(has("v_cmd") && has("w_cmd")))
      fail("no odometry source; expected a column pair ticks_l+ticks_r, omega_l+omega_r or v_cmd+w_cmd");
    const TrackMeta& m = data_.meta;
    const bool ticks = has("ticks_l") || has("ticks_r");
    if (ticks && !m.ticks_per_rev)
      fail("tick columns need metadata '# robot.ticks_per_rev: N' before the header, and it is missing");
    if (ticks || has("omega_l") || has("omega_r")) {
      std::string missing;
      if (!m.wheel_radius_left_m) missing += " robot.wheel_radius_left";
      if (!m.wheel_radius_right_m) missing += " robot.wheel_radius_right";
      if (!m.wheel_base_m) missing += " robot.wheel_base";
      if (!missing.empty())
        fail(fmt::format("wheel columns need metadata robot.wheel_radius_left, robot.wheel_radius_right and "
                         "robot.wheel_base before the header; missing:{}",
                         missing));
    }
  }

  void read_rows() {
    bool any = false;
    while (next_line()) {
      if (is_blank(line_) || is_hash_line(line_)) continue;
      parse_row(line_);
      any = true;
    }
    if (!any) {
      line_no_ = header_line_;
      fail("the header is not followed by any data row; expected at least one row");
    }
  }

  void parse_row(std::string_view line) {
    const std::size_t n = static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
    if (n != cols_.size())
      fail(fmt::format("row has {} cell{}, expected {} (one per header column)", n, n == 1 ? "" : "s",
                       cols_.size()));
    std::size_t start = 0;
    for (const Column& c : cols_) {
      const std::size_t comma = std::min(line.find(',', start), line.size());
      const std::string_view cell = trim(line.substr(start, comma - start));
      start = comma + 1;
      switch (c.kind) {
        case Kind::kIgnored: break;
        case Kind::kTime: data_.t.push_back(parse_time(cell)); break;
        case Kind::kTickL: data_.ticks_l.push_back(parse_tick(c, cell)); break;
        case Kind::kTickR: data_.ticks_r.push_back(parse_tick(c, cell)); break;
        case Kind::kReal: data_.col(c.col).push_back(parse_cell(c, cell)); break;
      }
    }
  }

  double parse_cell(const Column& c, std::string_view cell) const {
    if (cell.empty()) return std::numeric_limits<double>::quiet_NaN();
    double v = 0;
    switch (parse_real(cell, v)) {
      case NumParse::kOk: return v;
      case NumParse::kNonFinite:
        fail(fmt::format("non-finite value {} in column '{}'; expected a finite number or an empty cell",
                         quote(cell), c.name));
      case NumParse::kOutOfRange:
        fail(fmt::format("value {} in column '{}' is out of the range of a double; expected a finite number",
                         quote(cell), c.name));
      case NumParse::kBad: break;
    }
    fail(fmt::format("non-numeric value {} in column '{}'; expected a decimal number or an empty cell",
                     quote(cell), c.name));
  }

  double parse_time(std::string_view cell) {
    static const Column kT{"t", Kind::kTime, Col::kCount};
    if (cell.empty()) fail("empty 't' cell; expected a time [s] in every row");
    const double t = parse_cell(kT, cell);
    if (!data_.t.empty() && !(t > data_.t.back()))
      fail(fmt::format("t not strictly increasing: {} follows {} (line {}); expected a larger time", t,
                       data_.t.back(), last_row_line_));
    last_row_line_ = line_no_;
    return t;
  }

  std::int64_t parse_tick(const Column& c, std::string_view cell) const {
    if (cell.empty()) return kNoTick;
    std::int64_t v = 0;
    switch (parse_int64(cell, v)) {
      case NumParse::kOk:
        if (v == kNoTick)
          fail(
              fmt::format("tick value {} in column '{}' is reserved for 'no sample'; expected a count above it",
                          quote(cell), c.name));
        return v;
      case NumParse::kOutOfRange:
        fail(fmt::format("tick value {} in column '{}' overflows; expected a signed 64-bit integer",
                         quote(cell), c.name));
      default: break;
    }
    fail(fmt::format("tick value {} in column '{}' is not an integer; expected a signed 64-bit integer count",
                     quote(cell), c.name));
  }

  LineReader reader_;
  std::string file_;
  std::string line_;
  std::size_t line_no_ = 0;
  std::size_t header_line_ = 0;
  std::size_t last_row_line_ = 0;
  std::vector<Column> cols_;
  std::vector<std::pair<std::string, std::size_t>> seen_keys_;  // known metadata key -> line
  TrackData data_;
};

}  // namespace

Track parse_track(std::istream& in, std::string_view filename) { return Parser(in, filename).run(); }

Track read_track(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw TrackError(file, 0, "cannot open: it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw TrackError(file, 0, fmt::format("cannot open: {}", std::generic_category().message(errno)));
  Track track = parse_track(in, file);
  if (in.bad()) throw TrackError(file, 0, "read error");
  return track;
}

std::vector<Track> load_tracks(const std::vector<std::string>& paths) {
  std::vector<Track> tracks;
  for (const auto& p : paths) {
    try {
      tracks.push_back(read_track(p));
    } catch (const TrackError& e) {
      throw core::Failure(e.what());
    }
  }
  return tracks;
}

}  // namespace odotune::tracks

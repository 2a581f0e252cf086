#include <odotune/tracks/import_text.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <system_error>

#include <fmt/format.h>

#include <odotune/tracks/track_io.h>

namespace odotune::tracks::import_text {

bool is_file(const std::filesystem::path& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

LineReader::LineReader(const std::filesystem::path& path, std::string_view what) : file_(path.string()) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(st))
    throw TrackError(file_, 0, fmt::format("file not found (expected the {})", what));
  if (!std::filesystem::is_regular_file(st))
    throw TrackError(file_, 0, fmt::format("not a regular file (expected the {})", what));
  in_.open(path, std::ios::binary);
  if (!in_) throw TrackError(file_, 0, fmt::format("cannot open for reading (the {})", what));
  buf_.reserve(256);
}

bool LineReader::next(std::string_view& line) {
  buf_.clear();
  std::streambuf* sb = in_.rdbuf();
  bool got_any = false;
  for (;;) {
    const int c = sb->sbumpc();
    if (c == std::char_traits<char>::eof()) break;
    got_any = true;
    if (c == '\n') break;
    if (c == '\0') {
      ++line_no_;
      fail("contains a NUL byte (binary data?), expected a text line");
    }
    if (buf_.size() >= kMaxLineBytes) {
      ++line_no_;
      fail(fmt::format("line longer than {} bytes, expected a short text line", kMaxLineBytes));
    }
    buf_.push_back(static_cast<char>(c));
  }
  if (!got_any) {
    if (in_.bad()) fail("read error");
    return false;
  }
  ++line_no_;
  if (!buf_.empty() && buf_.back() == '\r') buf_.pop_back();
  std::string_view v(buf_);
  if (line_no_ == 1 && v.substr(0, 3) == "\xEF\xBB\xBF") v.remove_prefix(3);
  line = v;
  return true;
}

void LineReader::fail(const std::string& reason) const { throw TrackError(file_, line_no_, reason); }

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split_csv(std::string_view line) {
  std::vector<std::string_view> out;
  for (;;) {
    const auto pos = line.find(',');
    out.push_back(trim(line.substr(0, pos)));
    if (pos == std::string_view::npos) break;
    line.remove_prefix(pos + 1);
  }
  return out;
}

std::vector<std::string_view> split_ws(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

std::optional<double> to_double(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return std::nullopt;
  // from_chars accepts "inf"/"nan"; only digits, sign, point and exponent here.
  for (char c : s)
    if (!((c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E'))
      return std::nullopt;
  double v = 0.0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::optional<std::int64_t> to_int64(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return std::nullopt;
  std::int64_t v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<std::int64_t> decimal_to_ns(std::string_view s) {
  s = trim(s);
  bool neg = false;
  if (!s.empty() && (s.front() == '-' || s.front() == '+')) {
    neg = s.front() == '-';
    s.remove_prefix(1);
  }
  const auto dot = s.find('.');
  const std::string_view whole = s.substr(0, dot);
  const std::string_view frac = dot == std::string_view::npos ? std::string_view() : s.substr(dot + 1);
  if (whole.empty() || frac.size() > 9) return std::nullopt;
  if (dot != std::string_view::npos && frac.empty()) return std::nullopt;
  std::int64_t sec = 0;
  for (char c : whole) {
    if (c < '0' || c > '9') return std::nullopt;
    if (sec > (std::numeric_limits<std::int64_t>::max() / 1'000'000'000 - 9) / 10) return std::nullopt;
    sec = sec * 10 + (c - '0');
  }
  std::int64_t nano = 0;
  for (std::size_t i = 0; i < 9; ++i) {
    int d = 0;
    if (i < frac.size()) {
      if (frac[i] < '0' || frac[i] > '9') return std::nullopt;
      d = frac[i] - '0';
    }
    nano = nano * 10 + d;
  }
  const std::int64_t ns = sec * 1'000'000'000 + nano;
  return neg ? -ns : ns;
}

std::string ns_to_decimal(std::int64_t ns) {
  const bool neg = ns < 0;
  // |ns| fits: decimal_to_ns never produces INT64_MIN.
  const std::uint64_t a = neg ? static_cast<std::uint64_t>(-(ns + 1)) + 1u : static_cast<std::uint64_t>(ns);
  std::string frac = fmt::format("{:09d}", a % 1'000'000'000u);
  while (!frac.empty() && frac.back() == '0') frac.pop_back();
  std::string out = fmt::format("{}{}", neg ? "-" : "", a / 1'000'000'000u);
  if (!frac.empty()) out += "." + frac;
  return out;
}

std::string quote(std::string_view s) {
  constexpr std::size_t kMax = 40;
  std::string out = "'";
  for (std::size_t i = 0; i < s.size() && i < kMax; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c >= 0x7f || c == '\'' || c == '\\')
      out += fmt::format("\\x{:02x}", c);
    else
      out += static_cast<char>(c);
  }
  if (s.size() > kMax) out += "...";
  return out + "'";
}

std::string fmt_double(double v) { return fmt::format("{}", v); }

}  // namespace odotune::tracks::import_text

// UTIAS "Lost in the Woods" importer (see importers.h and
// ../shared/data/real/utias_lost_in_the_woods/SOURCE.md for the files).
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>

#include <odotune/tracks/import_text.h>
#include <odotune/tracks/importers.h>
#include <odotune/tracks/track_io.h>

namespace odotune::tracks {

namespace {

namespace fs = std::filesystem;
using namespace import_text;

constexpr const char* kLitwCitation =
    "UTIAS \"Lost in the Woods\" dataset (dataset2.mat), course AER1513 State Estimation for "
    "Aerospace Vehicles, Prof. T. D. Barfoot, University of Toronto Institute for Aerospace "
    "Studies; course text: T. D. Barfoot, State Estimation for Robotics, Cambridge University "
    "Press, 2017";
constexpr const char* kLitwLicence =
    "none stated (UTIAS AER1513 course data); check the terms before redistributing";

enum Field { kK, kT, kV, kOm, kX, kY, kTh, kValid, kNumFields };
constexpr std::array<const char*, kNumFields> kHeader = {"k",        "t_s",      "v_mps",       "om_radps",
                                                         "x_true_m", "y_true_m", "th_true_rad", "true_valid"};

// Scalars of litw_scalars.csv ("name,value" lines) as (name, value text).
std::vector<std::pair<std::string, std::string>> read_scalars(const fs::path& path) {
  LineReader r(path, "LITW scalars file litw_scalars.csv");
  std::vector<std::pair<std::string, std::string>> out;
  std::string_view line;
  bool header = true;
  while (r.next(line)) {
    if (trim(line).empty()) continue;
    const auto f = split_csv(line);
    if (header) {
      header = false;
      if (f.size() == 2 && f[0] == "name" && f[1] == "value") continue;
      r.fail("unexpected header, expected 'name,value'");
    }
    if (f.size() != 2 || f[0].empty()) r.fail(fmt::format("{} fields, expected 'name,value'", f.size()));
    for (char c : f[0])
      if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_'))
        r.fail(fmt::format("name {} is not an identifier, expected e.g. v_var", quote(f[0])));
    const auto v = to_double(f[1]);
    if (!v) r.fail(fmt::format("value {} of {} is not a finite number", quote(f[1]), quote(f[0])));
    out.emplace_back(std::string(f[0]), fmt_double(*v));
  }
  return out;
}

// Reads the header line: each field's column, and the header's width.
std::array<std::size_t, kNumFields> read_header(LineReader& r, const std::string& expected,
                                                std::size_t* width) {
  std::string_view line;
  if (!r.next(line)) throw TrackError(r.file(), 0, fmt::format("empty file, expected the header {}", expected));
  std::array<std::size_t, kNumFields> pos{};
  const auto head = split_csv(line);
  for (std::size_t f = 0; f < kNumFields; ++f) {
    std::size_t p = 0;
    while (p < head.size() && head[p] != kHeader[f]) ++p;
    if (p == head.size())
      r.fail(fmt::format("missing column '{}', expected the header {}", kHeader[f], expected));
    pos[f] = p;
  }
  *width = head.size();
  return pos;
}

// Reads the data rows into d; returns the number of samples without a valid
// ground-truth pose.
std::size_t read_rows(LineReader& r, const std::array<std::size_t, kNumFields>& pos, std::size_t width,
                      const std::string& expected, TrackData& d) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  auto& v = d.col(Col::v_cmd);
  auto& w = d.col(Col::w_cmd);
  auto& x = d.col(Col::gt_x);
  auto& y = d.col(Col::gt_y);
  auto& th = d.col(Col::gt_theta);
  std::size_t invalid = 0;
  std::string_view line;
  while (r.next(line)) {
    if (trim(line).empty()) continue;
    const auto f = split_csv(line);
    if (f.size() != width) r.fail(fmt::format("{} fields, expected {} ({})", f.size(), width, expected));
    const auto num = [&](Field which) {
      const auto val = to_double(f[pos[which]]);
      if (!val) r.fail(fmt::format("{} {} is not a finite number", kHeader[which], quote(f[pos[which]])));
      return *val;
    };
    const auto k = to_int64(f[pos[kK]]);
    if (!k || *k != static_cast<std::int64_t>(d.t.size()))
      r.fail(fmt::format("k {} is not the sample index, expected {} (rows 0, 1, 2, ...)", quote(f[pos[kK]]),
                         d.t.size()));
    const double t = num(kT);
    if (!d.t.empty() && !(t > d.t.back()))
      r.fail(fmt::format("t_s {} is not after the previous row's {}, expected strictly increasing time", t,
                         d.t.back()));
    const double valid = num(kValid);
    if (valid != 0.0 && valid != 1.0)
      r.fail(fmt::format("true_valid {}, expected 0 or 1", quote(f[pos[kValid]])));
    d.t.push_back(t);
    v.push_back(num(kV));
    w.push_back(num(kOm));
    if (valid == 1.0) {
      x.push_back(num(kX));
      y.push_back(num(kY));
      th.push_back(num(kTh));
    } else {  // pose cells of an invalid sample are not used, whatever they hold
      ++invalid;
      x.push_back(kNaN);
      y.push_back(kNaN);
      th.push_back(kNaN);
    }
  }
  return invalid;
}

void add_litw_metadata(const fs::path& series_csv, std::size_t invalid, TrackMeta& m) {
  const fs::path scalars_path = series_csv.parent_path() / "litw_scalars.csv";
  const bool have_scalars = is_file(scalars_path);
  m.name = "utias-lost-in-the-woods";
  m.origin = "recorded";
  m.body_velocity = BodyVelocitySource::measured;
  auto& e = m.extra;
  e.emplace_back("source",
                 fmt::format("UTIAS \"Lost in the Woods\" (AER1513 dataset2.mat, copied from github "
                             "samberg96/2D-ekf-example), CSV export {}{}: odometry v, om (10 Hz) and "
                             "ground-truth pose where true_valid = 1",
                             series_csv.filename().string(), have_scalars ? " and litw_scalars.csv" : ""));
  e.emplace_back("citation", kLitwCitation);
  e.emplace_back("licence", kLitwLicence);
  e.emplace_back("source.gt_invalid_samples", std::to_string(invalid));
  e.emplace_back("source.note", "v_cmd/w_cmd hold the base's odometry v, om (measured, biased), not commands; "
                                "gt cells are empty where true_valid = 0");
  if (have_scalars)
    for (auto& [name, value] : read_scalars(scalars_path)) e.emplace_back("litw." + name, value);
}

}  // namespace

Track import_litw(const fs::path& series_csv) {
  LineReader r(series_csv, "LITW series file litw_series.csv");
  const std::string expected = fmt::format("{}", fmt::join(kHeader, ","));
  std::size_t width = 0;
  const std::array<std::size_t, kNumFields> pos = read_header(r, expected, &width);
  TrackData d;
  const std::size_t invalid = read_rows(r, pos, width, expected, d);
  if (d.t.empty()) throw TrackError(r.file(), r.line_no(), "no data rows after the header");
  add_litw_metadata(series_csv, invalid, d.meta);
  return Track(std::move(d));
}

}  // namespace odotune::tracks

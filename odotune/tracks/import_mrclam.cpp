// UTIAS MRCLAM importer (see importers.h and
// ../shared/data/real/mrclam7/SOURCE.md for the file formats).
#include <algorithm>
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

constexpr int kMaxRobot = 5;  // MRCLAM: five robots per dataset (subjects 1-5)

constexpr const char* kMrclamCitation =
    "K. Y. K. Leung, Y. Halpern, T. D. Barfoot, H. H. T. Liu, \"The UTIAS Multi-Robot "
    "Cooperative Localization and Mapping Dataset\", International Journal of Robotics "
    "Research, 30(8):969-974, 2011";
constexpr const char* kMrclamLicence = "none stated; research data whose authors ask to be cited "
                                       "(http://asrl.utias.utoronto.ca/datasets/mrclam/)";

// One time-stamped line of a .dat file: time [ns since the epoch], values.
struct MrclamSample {
  std::int64_t ns;
  std::array<double, 3> v;
};

struct Series {
  std::vector<MrclamSample> samples;  // sorted by time, one per stamp (last one kept)
  std::size_t lines = 0;              // data lines read
  std::size_t duplicates = 0;         // samples dropped because their stamp repeated
  std::size_t out_of_order = 0;       // lines whose stamp was earlier than the line before
};

// Reads a whitespace-separated MRCLAM file: '#' comment lines, then lines of
// "time v1 .. vN" (N = names.size()).
Series read_series(const fs::path& path, const std::vector<const char*>& names, std::string_view what) {
  LineReader r(path, what);
  const std::string expected = fmt::format("time {}", fmt::join(names, " "));
  Series out;
  std::string_view line;
  while (r.next(line)) {
    const std::string_view tl = trim(line);
    if (tl.empty() || tl.front() == '#') continue;
    const auto f = split_ws(tl);
    if (f.size() != names.size() + 1)
      r.fail(fmt::format("{} fields, expected {} ({})", f.size(), names.size() + 1, expected));
    const auto ns = decimal_to_ns(f[0]);
    if (!ns)
      r.fail(fmt::format("time {} is not a plain decimal number of Unix seconds "
                         "(expected e.g. 1248446188.323)",
                         quote(f[0])));
    MrclamSample s{*ns, {}};
    for (std::size_t i = 0; i < names.size(); ++i) {
      const auto v = to_double(f[i + 1]);
      if (!v) r.fail(fmt::format("{} {} is not a finite number", names[i], quote(f[i + 1])));
      s.v[i] = *v;
    }
    if (!out.samples.empty() && s.ns < out.samples.back().ns) ++out.out_of_order;
    out.samples.push_back(s);
  }
  out.lines = out.samples.size();
  if (out.samples.empty())
    throw TrackError(r.file(), r.line_no(), fmt::format("no data lines, expected lines of: {}", expected));
  // Time order; a repeated stamp keeps the sample that came last in the file.
  std::stable_sort(out.samples.begin(), out.samples.end(),
                   [](const MrclamSample& a, const MrclamSample& b) { return a.ns < b.ns; });
  std::size_t k = 0;
  for (std::size_t i = 1; i < out.samples.size(); ++i) {
    if (out.samples[i].ns == out.samples[k].ns) {
      ++out.duplicates;
    } else {
      ++k;
    }
    out.samples[k] = out.samples[i];
  }
  out.samples.resize(k + 1);
  return out;
}

std::string folder_name(const fs::path& dir) {
  fs::path p = dir.lexically_normal();
  if (!p.has_filename()) p = p.parent_path();
  return p.filename().string();
}

// Merges the two sorted streams on their exact integer stamps into d's rows
// (time relative to the first stamp) and columns; returns the first stamp [ns].
std::int64_t merge_streams(const Series& odo, const Series& gt, const fs::path& odo_path, TrackData& d) {
  const std::size_t cap = odo.samples.size() + gt.samples.size();
  d.t.reserve(cap);
  std::vector<std::int64_t> ns;
  ns.reserve(cap);
  std::vector<double> v, w, x, y, th;
  for (auto* c : {&v, &w, &x, &y, &th}) c->reserve(cap);
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::size_t i = 0, j = 0;
  while (i < odo.samples.size() || j < gt.samples.size()) {
    const std::int64_t ti = i < odo.samples.size() ? odo.samples[i].ns
                                                   : std::numeric_limits<std::int64_t>::max();
    const std::int64_t tj = j < gt.samples.size() ? gt.samples[j].ns : std::numeric_limits<std::int64_t>::max();
    const std::int64_t now = std::min(ti, tj);
    ns.push_back(now);
    if (ti == now) {
      v.push_back(odo.samples[i].v[0]);
      w.push_back(odo.samples[i].v[1]);
      ++i;
    } else {
      v.push_back(kNaN);
      w.push_back(kNaN);
    }
    if (tj == now) {
      x.push_back(gt.samples[j].v[0]);
      y.push_back(gt.samples[j].v[1]);
      th.push_back(gt.samples[j].v[2]);
      ++j;
    } else {
      x.push_back(kNaN);
      y.push_back(kNaN);
      th.push_back(kNaN);
    }
  }
  const std::int64_t t0 = ns.front();
  for (std::size_t k = 0; k < ns.size(); ++k) {
    // Exact integer difference, then one correctly rounded division.
    d.t.push_back(static_cast<double>(ns[k] - t0) / 1e9);
    if (k > 0 && !(d.t[k] > d.t[k - 1]))
      throw TrackError(odo_path.string(), 0,
                       fmt::format("relative time not strictly increasing at {} s after {}", d.t[k],
                                   ns_to_decimal(t0)));
  }
  d.col(Col::v_cmd) = std::move(v);
  d.col(Col::w_cmd) = std::move(w);
  d.col(Col::gt_x) = std::move(x);
  d.col(Col::gt_y) = std::move(y);
  d.col(Col::gt_theta) = std::move(th);
  return t0;
}

void add_mrclam_metadata(const fs::path& dir, int robot, const std::string& odo_name,
                         const std::string& gt_name, const Series& odo, const Series& gt, std::int64_t t0,
                         TrackMeta& m) {
  const std::string folder = folder_name(dir);
  m.name = folder.rfind("mrclam", 0) == 0 || folder.rfind("MRCLAM", 0) == 0
               ? fmt::format("{}-robot{}", folder, robot)
               : fmt::format("mrclam-{}-robot{}", folder, robot);
  m.origin = "recorded";
  m.body_velocity = BodyVelocitySource::commanded;
  auto& e = m.extra;
  e.emplace_back("source", fmt::format("UTIAS Multi-Robot Cooperative Localization and Mapping Dataset "
                                       "(MRCLAM), folder {}, robot {} (iRobot Create): {} (commanded v, w), "
                                       "{} (Vicon pose)",
                                       folder, robot, odo_name, gt_name));
  e.emplace_back("citation", kMrclamCitation);
  e.emplace_back("licence", kMrclamLicence);
  e.emplace_back("source.t0_unix", ns_to_decimal(t0));
  e.emplace_back("source.odometry_samples", std::to_string(odo.samples.size()));
  e.emplace_back("source.groundtruth_samples", std::to_string(gt.samples.size()));
  e.emplace_back("source.odometry_duplicate_stamps", std::to_string(odo.duplicates));
  e.emplace_back("source.groundtruth_duplicate_stamps", std::to_string(gt.duplicates));
  if (odo.out_of_order + gt.out_of_order > 0)
    e.emplace_back("source.out_of_order_lines", fmt::format("odometry {}, groundtruth {} (sorted by time)",
                                                            odo.out_of_order, gt.out_of_order));
  e.emplace_back("source.note", "v_cmd/w_cmd are the logged velocity COMMANDS, not measured motion; a repeated "
                                "time stamp within one file keeps its last sample (counts in "
                                "source.*_duplicate_stamps); rows are the union of both files' stamps");
}

}  // namespace

Track import_mrclam(const fs::path& dir, int robot) {
  std::error_code ec;
  if (!fs::exists(dir, ec))
    throw TrackError(dir.string(), 0, "directory not found (expected an MRCLAM dataset folder)");
  if (!fs::is_directory(dir, ec))
    throw TrackError(dir.string(), 0, "not a directory (expected an MRCLAM dataset folder)");
  if (robot < 1 || robot > kMaxRobot)
    throw TrackError(dir.string(), 0,
                     fmt::format("robot {} does not exist, expected 1 to {}", robot, kMaxRobot));

  const std::string odo_name = fmt::format("Robot{}_Odometry.dat", robot);
  const std::string gt_name = fmt::format("Robot{}_Groundtruth.dat", robot);
  const Series odo = read_series(dir / odo_name, {"v", "omega"},
                                 fmt::format("MRCLAM odometry file {}", odo_name));
  const Series gt = read_series(dir / gt_name, {"x", "y", "theta"},
                                fmt::format("MRCLAM ground-truth file {}", gt_name));

  TrackData d;
  const std::int64_t t0 = merge_streams(odo, gt, dir / odo_name, d);
  add_mrclam_metadata(dir, robot, odo_name, gt_name, odo, gt, t0, d.meta);
  return Track(std::move(d));
}

}  // namespace odotune::tracks

// OptiOdom importer (see importers.h and
// ../shared/data/real/optiodom_diff/SOURCE.md for the file formats).
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <optional>
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

constexpr double kCycle_s = 0.05;  // robot control cycle (SOURCE.md: 20 Hz)

constexpr const char* kOptiodomCitation =
    "R. B. Sousa, M. R. Petry, P. G. Costa, A. P. Moreira, \"OptiOdom: a Generic Approach for "
    "Odometry Calibration of Wheeled Mobile Robots\", Journal of Intelligent & Robotic Systems "
    "105, 39 (2022), https://doi.org/10.1007/s10846-022-01630-3";
constexpr const char* kOptiodomLicence =
    "MIT, Copyright (c) 2021 Ricardo Sousa, Marcelo Petry, António Moreira, Paulo Costa "
    "(the LICENSE file must stay with the data)";

// ---- <id>_metadata.csv ------------------------------------------------------

struct MetaEntry {
  std::vector<std::string> values;  // trailing empty fields removed
  std::size_t line = 0;
};

struct RunMeta {
  std::string file;
  std::map<std::string, MetaEntry, std::less<>> entries;

  const MetaEntry& need(std::string_view key, std::string_view expected) const {
    const auto it = entries.find(key);
    if (it == entries.end() || it->second.values.empty())
      throw TrackError(file, 0, fmt::format("missing key '{}', expected a line '{},{}'", key, key, expected));
    return it->second;
  }
  // The index-th value of `key` as a positive finite number.
  double positive(std::string_view key, std::size_t index, std::string_view expected) const {
    const MetaEntry& e = need(key, expected);
    if (index >= e.values.size())
      throw TrackError(file, e.line,
                       fmt::format("'{}' has {} value(s), expected {}", key, e.values.size(), index + 1));
    const auto v = to_double(e.values[index]);
    if (!v || !(*v > 0.0))
      throw TrackError(file, e.line,
                       fmt::format("'{}' value {} is not a positive number (expected {})", key,
                                   quote(e.values[index]), expected));
    return *v;
  }
  // The index-th value of `key` as a finite number, if there is one.
  std::optional<double> optional_number(std::string_view key, std::size_t index) const {
    const auto it = entries.find(key);
    if (it == entries.end() || index >= it->second.values.size()) return std::nullopt;
    return to_double(it->second.values[index]);
  }
};

RunMeta read_meta(const fs::path& path) {
  LineReader r(path, "OptiOdom metadata file <id>_metadata.csv");
  RunMeta m;
  m.file = r.file();
  std::string_view line;
  while (r.next(line)) {
    if (trim(line).empty()) continue;
    auto f = split_csv(line);
    if (f[0].empty()) r.fail("empty key, expected 'key,value[,value...]'");
    MetaEntry e;
    e.line = r.line_no();
    for (std::size_t i = 1; i < f.size(); ++i) e.values.emplace_back(f[i]);
    while (!e.values.empty() && e.values.back().empty()) e.values.pop_back();
    m.entries[std::string(f[0])] = std::move(e);
  }
  return m;
}

// ---- <id>_run-NN.csv --------------------------------------------------------

struct RunRows {
  std::vector<double> t, x, y, th;
  std::vector<std::int64_t> dl, dr;  // per-cycle counts [ticks]
};

std::optional<std::int64_t> tick_count(std::string_view s) {
  if (auto i = to_int64(s)) return i;
  // Tolerate "19.0", but nothing fractional or beyond exact doubles.
  const auto v = to_double(s);
  if (v && std::floor(*v) == *v && std::fabs(*v) < 9.0e15) return static_cast<std::int64_t>(*v);
  return std::nullopt;
}

RunRows read_run(const fs::path& path) {
  LineReader r(path, "OptiOdom run file <id>_run-NN.csv");
  constexpr const char* kExpected = "time(s),xgt(m),ygt(m),thgt(rad),odoR,odoL";
  constexpr const char* kNames[] = {"time", "xgt", "ygt", "thgt", "odoR", "odoL"};
  RunRows out;
  std::string_view line;
  while (r.next(line)) {
    if (trim(line).empty()) continue;
    const auto f = split_csv(line);
    if (f.size() != 6) r.fail(fmt::format("{} fields, expected 6 ({})", f.size(), kExpected));
    double num[4];
    for (int i = 0; i < 4; ++i) {
      const auto v = to_double(f[static_cast<std::size_t>(i)]);
      if (!v)
        r.fail(fmt::format("{} {} is not a finite number", kNames[i], quote(f[static_cast<std::size_t>(i)])));
      num[i] = *v;
    }
    std::int64_t cnt[2];
    for (std::size_t i = 0; i < 2; ++i) {
      const auto c = tick_count(f[4 + i]);
      if (!c) r.fail(fmt::format("{} {} is not a whole tick count", kNames[4 + i], quote(f[4 + i])));
      cnt[i] = *c;
    }
    if (!out.t.empty() && !(num[0] > out.t.back()))
      r.fail(fmt::format("time {} is not after the previous row's {}, expected strictly increasing time",
                         num[0], out.t.back()));
    out.t.push_back(num[0]);
    out.x.push_back(num[1]);
    out.y.push_back(num[2]);
    out.th.push_back(num[3]);
    out.dr.push_back(cnt[0]);  // file order is R, then L
    out.dl.push_back(cnt[1]);
  }
  if (out.t.empty())
    throw TrackError(r.file(), r.line_no(), fmt::format("no data lines, expected lines of {}", kExpected));
  return out;
}

// ---- <id>.csv (robot log) ---------------------------------------------------

struct LogRow {
  double t;
  std::int64_t l, r;
  double vlin, omega;  // [ticks/cycle], [rad/cycle]
};

struct RobotLog {
  std::string method;        // "Method:" line of the header
  std::vector<LogRow> rows;  // block of run k only
};

// Reads run block `run` of the robot log. Throws TrackError on a malformed line.
RobotLog read_log(const fs::path& path, int run) {
  LineReader r(path, "OptiOdom robot log <id>.csv");
  RobotLog log;
  int block = 0;  // 0 = header
  bool seen = false;
  std::string_view line;
  while (r.next(line)) {
    const auto f = split_csv(line);
    if (f[0] == "Method:") {
      if (f.size() > 1) log.method = std::string(f[1]);
      continue;
    }
    if (f[0] == "Run:") {
      const auto k = f.size() > 1 ? to_int64(f[1]) : std::nullopt;
      if (!k) r.fail("'Run:' line without a run number, expected 'Run:,k'");
      block = static_cast<int>(*k);
      seen = seen || block == run;
      continue;
    }
    if (block != run || f[0].empty() || f[0].front() == '+') continue;
    if (f.size() < 8)
      r.fail(fmt::format("{} fields, expected at least 8 (time,odoL,odoR,xodo,yodo,thodo,vlin,omega)",
                         f.size()));
    const auto t = to_double(f[0]);
    const auto l = tick_count(f[1]);
    const auto rr = tick_count(f[2]);
    const auto v = to_double(f[6]);
    const auto w = to_double(f[7]);
    if (!t || !l || !rr || !v || !w) r.fail("non-numeric time, odoL, odoR, vlin or omega, expected numbers");
    log.rows.push_back({*t, *l, *rr, *v, *w});
  }
  if (!seen || log.rows.empty()) throw TrackError(r.file(), 0, fmt::format("no data for 'Run:,{}'", run));
  return log;
}

bool matches(const std::vector<LogRow>& rows, std::size_t off, const RunRows& run) {
  if (off + run.t.size() > rows.size()) return false;
  for (std::size_t i = 0; i < run.t.size(); ++i)
    if (rows[off + i].l != run.dl[i] || rows[off + i].r != run.dr[i]) return false;
  return true;
}

// Row offset of the run inside the log block, or nullopt with *why set.
std::optional<std::size_t> align(const RobotLog& log, const RunRows& run, const RunMeta& meta, int k,
                                 std::string* why) {
  const auto& rows = log.rows;
  std::vector<std::size_t> hits;
  for (std::size_t o = 0; o + run.t.size() <= rows.size() && hits.size() < 3; ++o)
    if (matches(rows, o, run)) hits.push_back(o);

  const auto ti = meta.optional_number("odo_ti", static_cast<std::size_t>(k - 1));
  const auto tf = meta.optional_number("odo_tf", static_cast<std::size_t>(k - 1));
  if (ti && tf) {
    // First and last log rows inside [odo_ti, odo_tf] (relative to the block
    // start), with half a cycle of tolerance.
    std::optional<std::size_t> first;
    std::size_t count = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const double rel = rows[i].t - rows.front().t;
      if (rel >= *ti - kCycle_s / 2 && rel <= *tf + kCycle_s / 2) {
        if (!first) first = i;
        ++count;
      }
    }
    if (first && count == run.t.size() && matches(rows, *first, run)) {
      *why = fmt::format("log run {} trimmed by odo_ti/odo_tf = {}/{} s reproduces odoL/odoR of all {} "
                         "rows{}",
                         k, *ti, *tf, run.t.size(),
                         hits.size() == 1 ? " (and no other offset does)"
                                          : " (the sequence also fits elsewhere)");
      return first;
    }
  }
  if (hits.size() == 1) {
    *why = fmt::format("odo_ti/odo_tf did not reproduce the run; the odoL/odoR sequence matches log run {} "
                       "at exactly one row offset ({})",
                       k, hits.front());
    return hits.front();
  }
  *why = hits.empty()
             ? fmt::format("not added: no row offset of log run {} reproduces the run's odoL/odoR", k)
             : fmt::format("not added: ambiguous, the run's odoL/odoR fits log run {} at several offsets", k);
  return std::nullopt;
}

// Splits "<id>_run-NN.csv" into id and NN; false if the name has another form.
bool parse_run_name(const std::string& name, std::string* id, int* k) {
  const std::string suffix = ".csv";
  if (name.size() <= suffix.size() || name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
    return false;
  const std::string stem = name.substr(0, name.size() - suffix.size());
  const auto pos = stem.rfind("_run-");
  if (pos == std::string::npos || pos == 0) return false;
  const std::string digits = stem.substr(pos + 5);
  if (digits.empty() || digits.size() > 4) return false;
  for (char c : digits)
    if (c < '0' || c > '9') return false;
  *id = stem.substr(0, pos);
  *k = std::stoi(digits);
  return *k >= 1;
}

void check_run_file(const fs::path& run_csv) {
  const std::string file = run_csv.string();
  std::error_code ec;
  if (!fs::exists(run_csv, ec))
    throw TrackError(file, 0, "file not found (expected an OptiOdom run file <id>_run-NN.csv)");
  if (!fs::is_regular_file(run_csv, ec))
    throw TrackError(file, 0, "not a regular file (expected an OptiOdom run file <id>_run-NN.csv)");
}

// The robot's geometry from the metadata.
struct Robot {
  double ngear = 0, enc_res = 0, base_m = 0, dl_m = 0, dr_m = 0;
  double tpr = 0;  // ticks per wheel revolution
};

Robot read_robot(const RunMeta& meta, int k, const std::string& file) {
  const MetaEntry& type = meta.need("type", "diff");
  if (type.values.front() != "diff")
    throw TrackError(meta.file, type.line,
                     fmt::format("robot type {} is not supported, expected 'diff' (differential drive)",
                                 quote(type.values.front())));
  Robot rb;
  rb.ngear = meta.positive("ngear", 0, "the gear ratio");
  rb.enc_res = meta.positive("encRes", 0, "encoder counts per motor revolution");
  rb.base_m = meta.positive("Li", 0, "the wheel separation [m]");
  // Di lists the left then the right diameter (the log header's dL0, dR0 order).
  const MetaEntry& di = meta.need("Di", "<left wheel diameter [m]>[,<right wheel diameter [m]>]");
  rb.dl_m = meta.positive("Di", 0, "the left wheel diameter [m]");
  rb.dr_m = di.values.size() > 1 ? meta.positive("Di", 1, "the right wheel diameter [m]") : rb.dl_m;
  if (const auto n = meta.optional_number("N", 0); n && k > *n)
    throw TrackError(file, 0, fmt::format("run {} but the metadata lists N = {} runs", k, *n));
  rb.tpr = rb.ngear * rb.enc_res;
  return rb;
}

// The per-cycle counts summed into cumulative ticks.
void cumulative_ticks(const RunRows& run, const std::string& file, TrackData& d) {
  const std::size_t n = run.t.size();
  d.ticks_l.resize(n);
  d.ticks_r.resize(n);
  std::int64_t cl = 0, cr = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (__builtin_add_overflow(cl, run.dl[i], &cl) || __builtin_add_overflow(cr, run.dr[i], &cr) ||
        cl == kNoTick || cr == kNoTick)
      throw TrackError(file, 0, "cumulative tick count leaves the signed 64-bit range");
    d.ticks_l[i] = cl;
    d.ticks_r[i] = cr;
  }
}

// What became of the robot log's velocity commands.
struct CommandsOutcome {
  std::string alignment;
  std::string method;
  bool have_cmd = false;
};

// Velocity commands from the robot log, when they align unambiguously.
CommandsOutcome add_commands(const fs::path& log_path, const RunRows& run, const RunMeta& meta, int k,
                             const Robot& rb, TrackData& d) {
  CommandsOutcome out;
  const std::size_t n = run.t.size();
  if (!is_file(log_path)) {
    out.alignment = fmt::format("not added: robot log {} not found", log_path.filename().string());
    return out;
  }
  try {
    const RobotLog log = read_log(log_path, k);
    out.method = log.method;
    if (const auto off = align(log, run, meta, k, &out.alignment)) {
      const double m_per_tick = std::numbers::pi * 0.5 * (rb.dl_m + rb.dr_m) / rb.tpr;
      auto& v = d.ensure(Col::v_cmd);
      auto& w = d.ensure(Col::w_cmd);
      for (std::size_t i = 0; i < n; ++i) {
        v[i] = log.rows[*off + i].vlin * m_per_tick / kCycle_s;
        w[i] = log.rows[*off + i].omega / kCycle_s;
      }
      out.have_cmd = true;
    }
  } catch (const TrackError& e) {
    out.alignment = fmt::format("not added: robot log unreadable: {}", e.what());
  }
  return out;
}

void add_optiodom_metadata(const fs::path& run_csv, const std::string& id, int k, const Robot& rb,
                           const CommandsOutcome& cmd, TrackMeta& m) {
  const fs::path dir = run_csv.parent_path();
  const fs::path meta_path = dir / (id + "_metadata.csv");
  const fs::path log_path = dir / (id + ".csv");
  const std::string experiment = dir.filename().string();
  const std::string kind = dir.parent_path().filename().string();
  m.name = fmt::format("optiodom-{}-run-{:02d}", id, k);
  m.origin = "recorded";
  m.ticks_per_rev = rb.tpr;
  m.wheel_radius_left_m = rb.dl_m / 2;
  m.wheel_radius_right_m = rb.dr_m / 2;
  m.wheel_base_m = rb.base_m;
  if (cmd.have_cmd) m.body_velocity = BodyVelocitySource::commanded;
  auto& e = m.extra;
  e.emplace_back("source",
                 fmt::format("OptiOdom (github sousarbarb/optiodom, data/diff), experiment {}{}, run {}: "
                             "{} (encoder ticks per 0.05 s cycle, OptiTrack ground truth resampled to "
                             "20 Hz, relative to the run start pose), {}{}",
                             kind.empty() ? "" : kind + "/", experiment, k, run_csv.filename().string(),
                             meta_path.filename().string(),
                             cmd.have_cmd ? ", " + log_path.filename().string() + " (velocity commands)" : ""));
  e.emplace_back("citation", kOptiodomCitation);
  e.emplace_back("licence", kOptiodomLicence);
  e.emplace_back("source.run", std::to_string(k));
  if (!cmd.method.empty()) e.emplace_back("source.method", cmd.method);
  e.emplace_back("source.ngear", fmt_double(rb.ngear));
  e.emplace_back("source.encRes", fmt_double(rb.enc_res));
  e.emplace_back("source.cmd_alignment", cmd.alignment);
  if (cmd.have_cmd)
    e.emplace_back("source.cmd_note",
                   "v_cmd = vlin*(pi*D/ticks_per_rev)/0.05 s, w_cmd = omega/0.05 s, with the nominal D; "
                   "each command sits on the cycle row it was logged on (no lag correction)");
}

}  // namespace

Track import_optiodom(const fs::path& run_csv) {
  const std::string file = run_csv.string();
  check_run_file(run_csv);
  std::string id;
  int k = 0;
  if (!parse_run_name(run_csv.filename().string(), &id, &k))
    throw TrackError(file, 0, "file name is not of the form <id>_run-NN.csv (an OptiOdom synchronised run)");
  const fs::path dir = run_csv.parent_path();
  const fs::path meta_path = dir / (id + "_metadata.csv");
  const fs::path log_path = dir / (id + ".csv");

  const RunMeta meta = read_meta(meta_path);
  const Robot rb = read_robot(meta, k, file);
  const RunRows run = read_run(run_csv);

  TrackData d;
  d.t = run.t;
  cumulative_ticks(run, file, d);
  d.col(Col::gt_x) = run.x;
  d.col(Col::gt_y) = run.y;
  d.col(Col::gt_theta) = run.th;
  const CommandsOutcome cmd = add_commands(log_path, run, meta, k, rb, d);
  add_optiodom_metadata(run_csv, id, k, rb, cmd, d.meta);
  return Track(std::move(d));
}

}  // namespace odotune::tracks

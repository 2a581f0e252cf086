// Importers on missing, truncated and garbled copies of the real files (built
// in a temporary folder), and import -> write_track -> read_track round trips.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <odotune/tracks/importers.h>
#include <odotune/tracks/track_io.h>

#include "support/temp_dir.h"

namespace odotune::tracks {
namespace {

using testing_support::TempDir;

namespace fs = std::filesystem;

const fs::path kRealDataDir = fs::path(ODOTUNE_SHARED_DIR) / "data" / "real";
const fs::path kMrclamDir = kRealDataDir / "mrclam7";
const fs::path kCircular = kRealDataDir / "optiodom_diff" / "circular" / "231220200146";
const fs::path kLitwDir = kRealDataDir / "utias_lost_in_the_woods" / "derived";

// A fresh temporary folder, removed at the end of the test.

std::vector<std::string> read_lines(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::vector<std::string> lines;
  std::string s;
  while (std::getline(in, s)) lines.push_back(s);
  return lines;
}

// Writes lines[0 .. n) joined by '\n', then `tail` (no newline after it).
void write_lines(const fs::path& p, const std::vector<std::string>& lines, std::size_t n,
                 const std::string& tail = "") {
  std::ofstream out(p, std::ios::binary);
  for (std::size_t i = 0; i < n && i < lines.size(); ++i) out << lines[i] << '\n';
  out << tail;
}

void copy_into(const fs::path& file, const fs::path& dir) { fs::copy_file(file, dir / file.filename()); }

// Runs f, expects a TrackError; returns it.
template <class F>
TrackError expect_track_error(F&& f) {
  try {
    f();
  } catch (const TrackError& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected TrackError, got: " << e.what();
    return TrackError("", 0, "");
  }
  ADD_FAILURE() << "expected TrackError, nothing thrown";
  return TrackError("", 0, "");
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// ---------------------------------------------------------------- missing ----

TEST(ImportErrors, MissingDirectoryAndFilesAreNamed) {
  const fs::path nowhere = fs::path(ODOTUNE_SHARED_DIR) / "no-such-folder";
  auto e = expect_track_error([&] { import_mrclam(nowhere, 1); });
  EXPECT_EQ(e.file(), nowhere.string());
  EXPECT_TRUE(contains(e.what(), "no-such-folder")) << e.what();
  EXPECT_TRUE(contains(e.reason(), "not found")) << e.what();

  e = expect_track_error([&] { import_mrclam(kMrclamDir, 9); });
  EXPECT_TRUE(contains(e.reason(), "robot 9")) << e.what();
  // Robots 4 and 5 of dataset 7 were not copied: the missing file is named.
  e = expect_track_error([&] { import_mrclam(kMrclamDir, 4); });
  EXPECT_TRUE(contains(e.file(), "Robot4_Odometry.dat")) << e.what();

  e = expect_track_error([&] { import_optiodom(kCircular / "231220200146_run-07.csv"); });
  EXPECT_TRUE(contains(e.file(), "231220200146_run-07.csv")) << e.what();
  EXPECT_TRUE(contains(e.reason(), "not found")) << e.what();
  e = expect_track_error([&] { import_optiodom(kCircular / "231220200146_metadata.csv"); });
  EXPECT_TRUE(contains(e.reason(), "_run-NN.csv")) << e.what();

  e = expect_track_error([&] { import_litw(kLitwDir / "missing_series.csv"); });
  EXPECT_TRUE(contains(e.file(), "missing_series.csv")) << e.what();
  e = expect_track_error([&] { import_litw(kLitwDir); });  // a directory
  EXPECT_TRUE(contains(e.reason(), "not a regular file")) << e.what();
}

TEST(ImportErrors, OptiOdomNeedsItsMetadata) {
  TempDir dir("opti-nometa");
  copy_into(kCircular / "231220200146_run-01.csv", dir.path());
  const auto e = expect_track_error([&] { import_optiodom(dir.path() / "231220200146_run-01.csv"); });
  EXPECT_TRUE(contains(e.file(), "231220200146_metadata.csv")) << e.what();
}

// ------------------------------------------------------------- corrupted -----

TEST(ImportErrors, MrclamTruncatedAndGarbledCopies) {
  TempDir dir("mrclam");
  copy_into(kMrclamDir / "Robot1_Groundtruth.dat", dir.path());
  const auto odo = read_lines(kMrclamDir / "Robot1_Odometry.dat");
  // Truncated mid-line after 1000 complete lines: line 1001 is "1248446...".
  write_lines(dir.path() / "Robot1_Odometry.dat", odo, 1000, odo[1000].substr(0, 12));
  auto e = expect_track_error([&] { import_mrclam(dir.path(), 1); });
  EXPECT_EQ(e.line(), 1001u) << e.what();
  EXPECT_TRUE(contains(e.file(), "Robot1_Odometry.dat")) << e.what();
  EXPECT_TRUE(contains(e.reason(), "expected 3")) << e.what();

  // Garbled value on line 500.
  std::vector<std::string> bad = odo;
  bad[499] = "1248446195.000 \t 0.08x6 \t 0.1";
  fs::remove(dir.path() / "Robot1_Odometry.dat");
  write_lines(dir.path() / "Robot1_Odometry.dat", bad, bad.size());
  e = expect_track_error([&] { import_mrclam(dir.path(), 1); });
  EXPECT_EQ(e.line(), 500u) << e.what();
  EXPECT_TRUE(contains(e.reason(), "0.08x6")) << e.what();

  // An epoch stamp in exponent form cannot be subtracted exactly: refused.
  bad = odo;
  bad[9] = "1.248446195e9 0.01 0.0";
  fs::remove(dir.path() / "Robot1_Odometry.dat");
  write_lines(dir.path() / "Robot1_Odometry.dat", bad, bad.size());
  e = expect_track_error([&] { import_mrclam(dir.path(), 1); });
  EXPECT_EQ(e.line(), 10u) << e.what();

  // Only the comment header left: no data.
  fs::remove(dir.path() / "Robot1_Odometry.dat");
  write_lines(dir.path() / "Robot1_Odometry.dat", odo, 4);
  e = expect_track_error([&] { import_mrclam(dir.path(), 1); });
  EXPECT_TRUE(contains(e.reason(), "no data")) << e.what();
}

TEST(ImportErrors, OptiOdomGarbledRunAndUnmatchedLog) {
  TempDir dir("opti");
  for (const char* f : {"231220200146_run-01.csv", "231220200146_metadata.csv"})
    copy_into(kCircular / f, dir.path());
  const fs::path run = dir.path() / "231220200146_run-01.csv";

  // Without the robot log: ticks and GT, no commands, and the reason is noted.
  Track tr = import_optiodom(run);
  EXPECT_TRUE(tr.has_ticks());
  EXPECT_FALSE(tr.has_cmd());
  EXPECT_TRUE(contains(*tr.meta().get("source.cmd_alignment"), "not found"));

  // A log whose run 1 no longer reproduces the run's odoL/odoR: commands left out.
  auto log = read_lines(kCircular / "231220200146.csv");
  ASSERT_GT(log.size(), 20u);
  ASSERT_EQ(log[10].rfind("4871.20000000896,23,19,", 0), 0u);  // log row of odoL=23, odoR=19
  log[10].replace(0, 22, "4871.20000000896,24,19");
  write_lines(dir.path() / "231220200146.csv", log, log.size());
  tr = import_optiodom(run);
  EXPECT_FALSE(tr.has_cmd());
  EXPECT_EQ(tr.meta().get("source.cmd_alignment")->rfind("not added", 0), 0u)
      << *tr.meta().get("source.cmd_alignment");

  // Garbled run file: a letter in odoL on line 100; a missing field on line 7.
  auto lines = read_lines(kCircular / "231220200146_run-01.csv");
  auto bad = lines;
  bad[99] += "x";
  fs::remove(run);
  write_lines(run, bad, bad.size());
  auto e = expect_track_error([&] { import_optiodom(run); });
  EXPECT_EQ(e.line(), 100u) << e.what();
  EXPECT_TRUE(contains(e.reason(), "odoL")) << e.what();
  fs::remove(run);
  write_lines(run, lines, 6, "0.3,0.01,0.0");
  e = expect_track_error([&] { import_optiodom(run); });
  EXPECT_EQ(e.line(), 7u) << e.what();

  // Time going backwards.
  bad = lines;
  std::swap(bad[40], bad[41]);
  fs::remove(run);
  write_lines(run, bad, bad.size());
  e = expect_track_error([&] { import_optiodom(run); });
  EXPECT_EQ(e.line(), 42u) << e.what();
}

TEST(ImportErrors, OptiOdomMetadataWithBomAndBadValues) {
  TempDir dir("opti-meta");
  copy_into(kCircular / "231220200146_run-02.csv", dir.path());
  const fs::path run = dir.path() / "231220200146_run-02.csv";
  const fs::path meta = dir.path() / "231220200146_metadata.csv";
  const auto lines = read_lines(kCircular / "231220200146_metadata.csv");
  // A BOM and CRLF line ends are accepted (trailing commas are in the original).
  {
    std::ofstream out(meta, std::ios::binary);
    out << "\xEF\xBB\xBF";
    for (const auto& l : lines) out << l << "\r\n";
  }
  const Track tr = import_optiodom(run);
  EXPECT_DOUBLE_EQ(*tr.meta().wheel_base_m, 0.2);
  // A non-numeric gear ratio names the line.
  auto bad = lines;
  ASSERT_EQ(bad[1].rfind("ngear,", 0), 0u);
  bad[1] = "ngear,fourty,";
  fs::remove(meta);
  write_lines(meta, bad, bad.size());
  auto e = expect_track_error([&] { import_optiodom(run); });
  EXPECT_EQ(e.line(), 2u) << e.what();
  EXPECT_TRUE(contains(e.reason(), "fourty")) << e.what();
  // A missing wheel separation names the key.
  bad = lines;
  ASSERT_EQ(bad[3].rfind("Li,", 0), 0u);
  bad.erase(bad.begin() + 3);
  fs::remove(meta);
  write_lines(meta, bad, bad.size());
  e = expect_track_error([&] { import_optiodom(run); });
  EXPECT_TRUE(contains(e.reason(), "'Li'")) << e.what();
}

TEST(ImportErrors, LitwTruncatedGarbledAndWithoutScalars) {
  TempDir dir("litw");
  const fs::path series = dir.path() / "litw_series.csv";
  const auto lines = read_lines(kLitwDir / "litw_series.csv");
  write_lines(series, lines, 501, lines[501].substr(0, 20));  // header + 500 rows, then half a row
  auto e = expect_track_error([&] { import_litw(series); });
  EXPECT_EQ(e.line(), 502u) << e.what();

  // No litw_scalars.csv beside it: fine, the variance keys are simply absent.
  fs::remove(series);
  write_lines(series, lines, 501);
  const Track tr = import_litw(series);
  EXPECT_EQ(tr.size(), 500u);
  EXPECT_FALSE(tr.meta().get("litw.v_var").has_value());

  // Non-increasing t (row k = 10 repeats the previous time) and a bad flag.
  auto bad = lines;
  bad[11] = "10,0.9,0,0,0,0,0,1";
  fs::remove(series);
  write_lines(series, bad, bad.size());
  e = expect_track_error([&] { import_litw(series); });
  EXPECT_EQ(e.line(), 12u) << e.what();
  EXPECT_TRUE(contains(e.reason(), "increasing")) << e.what();
  bad = lines;
  bad[21] = "20,2.0,0,0,0,0,0,2";
  fs::remove(series);
  write_lines(series, bad, bad.size());
  e = expect_track_error([&] { import_litw(series); });
  EXPECT_EQ(e.line(), 22u) << e.what();

  // A header without the expected columns.
  bad = lines;
  bad[0] = "k,t,v,om,x,y,th,valid";
  fs::remove(series);
  write_lines(series, bad, bad.size());
  e = expect_track_error([&] { import_litw(series); });
  EXPECT_EQ(e.line(), 1u) << e.what();
  EXPECT_TRUE(contains(e.reason(), "t_s")) << e.what();
}

TEST(ImportErrors, BinaryGarbageIsOneCleanError) {
  TempDir dir("garbage");
  std::mt19937 rng(20240611u);
  std::uniform_int_distribution<int> byte(0, 255);
  const auto garbage = [&](const fs::path& p) {
    std::ofstream out(p, std::ios::binary);
    for (int i = 0; i < 200000; ++i) out.put(static_cast<char>(byte(rng)));
  };
  garbage(dir.path() / "Robot1_Odometry.dat");
  copy_into(kMrclamDir / "Robot1_Groundtruth.dat", dir.path());
  auto e = expect_track_error([&] { import_mrclam(dir.path(), 1); });
  EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  EXPECT_GE(e.line(), 1u);

  garbage(dir.path() / "litw_series.csv");
  e = expect_track_error([&] { import_litw(dir.path() / "litw_series.csv"); });
  EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);

  garbage(dir.path() / "x_run-01.csv");
  copy_into(kCircular / "231220200146_metadata.csv", dir.path());
  fs::rename(dir.path() / "231220200146_metadata.csv", dir.path() / "x_metadata.csv");
  e = expect_track_error([&] { import_optiodom(dir.path() / "x_run-01.csv"); });
  EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
}

// ------------------------------------------------------------ round trip -----

void expect_same(const Track& a, const Track& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.t(), b.t());
  EXPECT_EQ(a.ticks_l(), b.ticks_l());
  EXPECT_EQ(a.ticks_r(), b.ticks_r());
  for (int c = 0; c < kNumCols; ++c) {
    const auto& x = a.col(static_cast<Col>(c));
    const auto& y = b.col(static_cast<Col>(c));
    ASSERT_EQ(x.size(), y.size()) << column_name(static_cast<Col>(c));
    for (std::size_t i = 0; i < x.size(); ++i)
      ASSERT_TRUE((std::isnan(x[i]) && std::isnan(y[i])) || x[i] == y[i])
          << column_name(static_cast<Col>(c)) << " row " << i;
  }
  EXPECT_EQ(a.meta().name, b.meta().name);
  EXPECT_EQ(a.meta().origin, b.meta().origin);
  EXPECT_EQ(a.meta().ticks_per_rev, b.meta().ticks_per_rev);
  EXPECT_EQ(a.meta().wheel_radius_left_m, b.meta().wheel_radius_left_m);
  EXPECT_EQ(a.meta().wheel_radius_right_m, b.meta().wheel_radius_right_m);
  EXPECT_EQ(a.meta().wheel_base_m, b.meta().wheel_base_m);
  for (const auto& [k, v] : a.meta().extra) EXPECT_EQ(b.meta().get(k), v) << k;
}

TEST(ImportRoundTrip, WriteThenReadGivesTheSameTrack) {
  TempDir dir("roundtrip");
  const Track tracks[] = {import_mrclam(kMrclamDir, 2), import_optiodom(kCircular / "231220200146_run-01.csv"),
                          import_litw(kLitwDir / "litw_series.csv")};
  const char* names[] = {"mrclam.csv", "optiodom.csv", "litw.csv"};
  for (std::size_t i = 0; i < 3; ++i) {
    const Track& tr = tracks[i];
    const fs::path out = dir.path() / names[i];
    write_track(tr, out);
    const Track back = read_track(out);
    expect_same(tr, back);
  }
}

}  // namespace
}  // namespace odotune::tracks

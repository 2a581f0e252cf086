// Tests of the track reader and writer against ../shared/specs/track-format.md:
// every error rule of the spec (with its line number and reason), the spec's
// example, tolerated input variants and the writer's file handling. The
// randomised round-trip and mutation tests are in test_track_io_random.cpp.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <unistd.h>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/tracks/track_io.h>

#include "support/temp_dir.h"

namespace odotune::tracks {
namespace {

using testing_support::TempDir;

namespace fs = std::filesystem;
using ::testing::HasSubstr;

Track parse(const std::string& text, std::string_view file = "mem.csv") {
  std::istringstream in(text);
  return parse_track(in, file);
}

// The TrackError that parsing `text` throws (a test failure if none).
TrackError error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const TrackError& e) {
    return e;
  }
  ADD_FAILURE() << "expected a TrackError for:\n" << text;
  return TrackError("", 0, "");
}

// Lines 1..6: format and robot metadata.
const std::string kMeta = "# format: odotune-track/1\n"
                          "# name: base\n"
                          "# robot.ticks_per_rev: 1000\n"
                          "# robot.wheel_radius_left: 0.1\n"
                          "# robot.wheel_radius_right: 0.11\n"
                          "# robot.wheel_base: 0.5\n";
// Line 7: header; data rows start at line 8.
const std::string kHeader = "t,ticks_l,ticks_r,gyro_z\n";

// ---------------------------------------------------------------- errors ---

TEST(TrackIoErrors, MissingFormatLine) {
  const auto e = error_of("# name: x\nt,v_cmd,w_cmd\n0,1,2\n");
  EXPECT_EQ(e.line(), 1u);
  EXPECT_THAT(e.reason(), HasSubstr("missing format line, expected '# format: odotune-track/1'"));
  EXPECT_EQ(std::string(e.what()), "mem.csv:1: " + e.reason());
  EXPECT_EQ(error_of("t,v_cmd,w_cmd\n0,1,2\n").line(), 1u);
  // The format line must be the first one.
  EXPECT_EQ(error_of("\n# format: odotune-track/1\nt,v_cmd,w_cmd\n0,1,2\n").line(), 1u);
  const auto empty = error_of("");
  EXPECT_EQ(empty.line(), 1u);
  EXPECT_THAT(empty.reason(), HasSubstr("missing format line"));
}

TEST(TrackIoErrors, UnknownFormat) {
  const auto e = error_of("# format: odotune-track/2\nt,v_cmd,w_cmd\n0,1,2\n");
  EXPECT_EQ(e.line(), 1u);
  EXPECT_THAT(e.reason(), HasSubstr("unknown format 'odotune-track/2'"));
  EXPECT_THAT(e.reason(), HasSubstr("odotune-track/1"));
}

TEST(TrackIoErrors, MissingT) {
  const auto e = error_of(kMeta + "time,ticks_l,ticks_r\n0,1,2\n");
  EXPECT_EQ(e.line(), 7u);
  EXPECT_THAT(e.reason(), HasSubstr("missing column 't'"));
}

TEST(TrackIoErrors, NonIncreasingT) {
  const auto e = error_of(kMeta + kHeader + "0.0,0,0,0\n0.02,1,1,0\n0.01,2,2,0\n");
  EXPECT_EQ(e.line(), 10u);
  EXPECT_THAT(e.reason(), HasSubstr("not strictly increasing"));
  EXPECT_THAT(e.reason(), HasSubstr("0.01"));
  EXPECT_THAT(e.reason(), HasSubstr("0.02"));
  EXPECT_THAT(e.reason(), HasSubstr("line 9"));
}

TEST(TrackIoErrors, EqualT) {
  const auto e = error_of(kMeta + kHeader + "0.5,0,0,0\n# comment\n\n0.5,1,1,0\n");
  EXPECT_EQ(e.line(), 11u);
  EXPECT_THAT(e.reason(), HasSubstr("not strictly increasing: 0.5 follows 0.5"));
}

TEST(TrackIoErrors, EmptyTCell) {
  const auto e = error_of(kMeta + kHeader + "0,0,0,0\n ,1,1,0\n");
  EXPECT_EQ(e.line(), 9u);
  EXPECT_THAT(e.reason(), HasSubstr("empty 't' cell"));
}

TEST(TrackIoErrors, NonNumericCell) {
  const auto e = error_of(kMeta + kHeader + "0,0,0,0\n0.1,1,1,abc\n");
  EXPECT_EQ(e.line(), 9u);
  EXPECT_THAT(e.reason(), HasSubstr("non-numeric value 'abc' in column 'gyro_z'"));
  for (const char* cell : {"1,5", "0x10", "1e", "--1", "+-1", "1.2.3", "e5", "1 2"}) {
    SCOPED_TRACE(cell);
    const auto f = error_of(kMeta + "t,v_cmd,w_cmd,gyro_z\n0,1,1,0\n1,1,1," + cell + "\n");
    EXPECT_EQ(f.line(), 9u);
  }
  EXPECT_THAT(error_of(kMeta + kHeader + "x,0,0,0\n").reason(), HasSubstr("in column 't'"));
}

TEST(TrackIoErrors, NonFiniteCell) {
  for (const char* cell : {"nan", "NaN", "inf", "-inf", "infinity", "-nan"}) {
    SCOPED_TRACE(cell);
    const auto e = error_of(kMeta + kHeader + "0,0,0,0\n0.1,1,1," + cell + "\n");
    EXPECT_EQ(e.line(), 9u);
    EXPECT_THAT(e.reason(), HasSubstr("non-finite value '" + std::string(cell) + "' in column 'gyro_z'"));
  }
  const auto t = error_of(kMeta + kHeader + "0,0,0,0\ninf,1,1,0\n");
  EXPECT_EQ(t.line(), 9u);
  EXPECT_THAT(t.reason(), HasSubstr("column 't'"));
  const auto huge = error_of(kMeta + kHeader + "0,0,0,1e999\n");
  EXPECT_EQ(huge.line(), 8u);
  EXPECT_THAT(huge.reason(), HasSubstr("out of the range"));
}

TEST(TrackIoErrors, TooFewCells) {
  const auto e = error_of(kMeta + kHeader + "0,0,0,0\n0.1,1,1\n");
  EXPECT_EQ(e.line(), 9u);
  EXPECT_THAT(e.reason(), HasSubstr("row has 3 cells, expected 4"));
}

TEST(TrackIoErrors, TooManyCells) {
  const auto e = error_of(kMeta + kHeader + "0,0,0,0,\n");
  EXPECT_EQ(e.line(), 8u);
  EXPECT_THAT(e.reason(), HasSubstr("row has 5 cells, expected 4"));
}

TEST(TrackIoErrors, TickColumnWithoutTicksPerRev) {
  const auto e = error_of(
      "# format: odotune-track/1\n# robot.wheel_radius_left: 0.1\n# robot.wheel_radius_right: 0.1\n"
      "# robot.wheel_base: 0.5\nt,ticks_l,ticks_r\n0,0,0\n");
  EXPECT_EQ(e.line(), 5u);
  EXPECT_THAT(e.reason(), HasSubstr("robot.ticks_per_rev"));
  EXPECT_THAT(e.reason(), HasSubstr("tick columns"));
}

TEST(TrackIoErrors, WheelColumnsWithoutGeometry) {
  const auto e = error_of(
      "# format: odotune-track/1\n# robot.wheel_radius_left: 0.1\nt,omega_l,omega_r\n0,0,0\n");
  EXPECT_EQ(e.line(), 3u);
  EXPECT_THAT(e.reason(), HasSubstr("missing: robot.wheel_radius_right robot.wheel_base"));
  // v_cmd/w_cmd alone need no robot metadata.
  EXPECT_EQ(parse("# format: odotune-track/1\nt,v_cmd,w_cmd\n0,0,0\n").size(), 1u);
}

TEST(TrackIoErrors, NoOdometrySource) {
  const auto e = error_of(kMeta + "t,gyro_z,gt_x,gt_y\n0,0,0,0\n");
  EXPECT_EQ(e.line(), 7u);
  EXPECT_THAT(e.reason(), HasSubstr("no odometry source"));
  // Half a pair is not a source either.
  EXPECT_THAT(error_of(kMeta + "t,ticks_l,omega_r,v_cmd\n0,0,0,0\n").reason(), HasSubstr("no odometry source"));
}

TEST(TrackIoErrors, MisspelledColumnWithSuggestion) {
  const auto e = error_of(kMeta + "t,v_cmd,w_cmd,gyro_zz\n0,0,0,0\n");
  EXPECT_EQ(e.line(), 7u);
  EXPECT_EQ(e.reason(), "unknown column 'gyro_zz'; did you mean 'gyro_z'?");
  // {typo, meant}; the odometry columns of the header avoid the meant name,
  // since names already in the header are not suggested.
  const std::pair<const char*, const char*> cases[] = {
      {"Gyro_Z", "gyro_z"}, {"gyroz", "gyro_z"},   {"gyro", "gyro_z"},        {"gyro_z_rad", "gyro_z"},
      {"v_cdm", "v_cmd"},   {"tick_l", "ticks_l"}, {"ticks_left", "ticks_l"}, {"gt_theat", "gt_theta"},
      {"aps_z", "aps_x"},   {"power", "power_l"},  {"omegal", "omega_l"},     {"raw_gyro_z", "gyro_z"}};
  for (const auto& [typo, meant] : cases) {
    SCOPED_TRACE(typo);
    const std::string odo = std::string_view(meant) == "v_cmd" ? "omega_l,omega_r" : "v_cmd,w_cmd";
    const auto f = error_of(kMeta + "t," + odo + "," + typo + "\n0,0,0,0\n");
    EXPECT_EQ(f.line(), 7u);
    EXPECT_EQ(f.reason(), fmt::format("unknown column '{}'; did you mean '{}'?", typo, meant));
  }
  // "T" for a missing t is caught as a misspelling, not as "missing t".
  EXPECT_THAT(error_of(kMeta + "T,v_cmd,w_cmd\n0,0,0\n").reason(), HasSubstr("did you mean 't'?"));
  EXPECT_THAT(error_of(kMeta + "t[s],v_cmd,w_cmd\n0,0,0\n").reason(), HasSubstr("did you mean 't'?"));
}

TEST(TrackIoErrors, NonIntegerTick) {
  const auto e = error_of(kMeta + kHeader + "0,0,0,0\n0.1,1.5,2,0\n");
  EXPECT_EQ(e.line(), 9u);
  EXPECT_THAT(e.reason(), HasSubstr("tick value '1.5' in column 'ticks_l' is not an integer"));
  EXPECT_THAT(error_of(kMeta + kHeader + "0,0,1e3,0\n").reason(), HasSubstr("'1e3' in column 'ticks_r'"));
  const auto big = error_of(kMeta + kHeader + "0,9223372036854775808,0,0\n");
  EXPECT_EQ(big.line(), 8u);
  EXPECT_THAT(big.reason(), HasSubstr("overflows"));
  EXPECT_THAT(error_of(kMeta + kHeader + "0,-9223372036854775809,0,0\n").reason(), HasSubstr("overflows"));
  EXPECT_THAT(error_of(kMeta + kHeader + "0,-9223372036854775808,0,0\n").reason(), HasSubstr("reserved"));
}

TEST(TrackIoErrors, BadHeaderNames) {
  const auto dup = error_of(kMeta + "t,v_cmd,w_cmd,v_cmd\n0,0,0,0\n");
  EXPECT_EQ(dup.line(), 7u);
  EXPECT_THAT(dup.reason(), HasSubstr("duplicate column 'v_cmd' (positions 2 and 4)"));
  const auto empty = error_of(kMeta + "t,v_cmd,w_cmd,\n0,0,0,\n");
  EXPECT_EQ(empty.line(), 7u);
  EXPECT_THAT(empty.reason(), HasSubstr("empty column name at position 4"));
  std::string wide = "t,v_cmd,w_cmd";
  for (int i = 0; i < 300; ++i) wide += fmt::format(",extra{}", i);
  EXPECT_THAT(error_of(kMeta + wide + "\n").reason(), HasSubstr("at most 256"));
}

TEST(TrackIoErrors, BadRobotMetadata) {
  for (const char* value : {"-0.5", "0", "abc", "nan", "inf", "", "0.5 m"}) {
    SCOPED_TRACE(value);
    const auto e = error_of(fmt::format(
        "# format: odotune-track/1\n# name: n\n# robot.wheel_base: {}\nt,v_cmd,w_cmd\n0,0,0\n", value));
    EXPECT_EQ(e.line(), 3u);
    EXPECT_THAT(e.reason(), HasSubstr("robot.wheel_base must be a finite positive number"));
  }
  const auto dup = error_of(kMeta + "# robot.wheel_base: 0.6\n" + kHeader + "0,0,0,0\n");
  EXPECT_EQ(dup.line(), 7u);
  EXPECT_THAT(dup.reason(), HasSubstr("duplicate metadata key 'robot.wheel_base' (first given on line 6)"));
}

TEST(TrackIoErrors, NoHeader) {
  const auto e = error_of(kMeta + "\n# only comments\n");
  EXPECT_EQ(e.line(), 8u);
  EXPECT_THAT(e.reason(), HasSubstr("no header line"));
  EXPECT_THAT(error_of("# format: odotune-track/1").reason(), HasSubstr("no header line"));
}

// Policy (track_io.h): a header without data rows is rejected.
TEST(TrackIoErrors, HeaderWithoutRows) {
  const auto e = error_of(kMeta + kHeader + "# nothing recorded\n\n");
  EXPECT_EQ(e.line(), 7u);
  EXPECT_THAT(e.reason(), HasSubstr("not followed by any data row"));
}

TEST(TrackIoErrors, OverlongLine) {
  const auto e = error_of(kMeta + kHeader + "0,0,0,0\n" + std::string(3u << 20, '1') + "\n");
  EXPECT_EQ(e.line(), 9u);
  EXPECT_THAT(e.reason(), HasSubstr("line longer than 1048576 bytes"));
  // A long unterminated last line as well.
  EXPECT_EQ(error_of(kMeta + std::string(2u << 20, ',')).line(), 7u);
}

TEST(TrackIoErrors, ReasonQuotesLongAndBinaryTextSafely) {
  const auto e = error_of(kMeta + kHeader + "0,0,0," + std::string(5000, 'x') + "\r\x01\n");
  EXPECT_LT(e.reason().size(), 200u);
  EXPECT_EQ(std::string(e.what()).find_first_of("\r\n\x01"), std::string::npos);
}

TEST(TrackIoErrors, UnopenableFile) {
  const fs::path missing = fs::temp_directory_path() / "odotune-io-no-such-dir" / "none.csv";
  try {
    read_track(missing);
    FAIL() << "no error";
  } catch (const TrackError& e) {
    EXPECT_EQ(e.line(), 0u);
    EXPECT_EQ(e.file(), missing.string());
    EXPECT_THAT(e.reason(), HasSubstr("cannot open"));
    EXPECT_EQ(std::string(e.what()), missing.string() + ": " + e.reason());
  }
  EXPECT_THROW(read_track(fs::temp_directory_path()), TrackError);
}

// ----------------------------------------------------------------- reads ---

const std::string kSpecExample = "# format: odotune-track/1\n"
                                 "# name: square-2m\n"
                                 "# origin: simulated\n"
                                 "# robot.ticks_per_rev: 8800\n"
                                 "# robot.wheel_radius_left: 0.32\n"
                                 "# robot.wheel_radius_right: 0.32\n"
                                 "# robot.wheel_base: 0.65\n"
                                 "t,ticks_l,ticks_r,gyro_z,aps_x,aps_y,gt_x,gt_y,gt_theta\n"
                                 "0.00,0,0,0.0003,0.012,-0.031,0,0,0\n"
                                 "0.01,2,3,0.0011,,,0.0001,0,0.00002\n";

// The values of the spec's example, as written there.
void expect_spec_example(const Track& tr) {
  EXPECT_EQ(tr.name(), "square-2m");
  EXPECT_EQ(tr.meta().origin, "simulated");
  EXPECT_EQ(tr.meta().ticks_per_rev, 8800.0);
  EXPECT_EQ(tr.meta().wheel_radius_left_m, 0.32);
  EXPECT_EQ(tr.meta().wheel_radius_right_m, 0.32);
  EXPECT_EQ(tr.meta().wheel_base_m, 0.65);
  EXPECT_TRUE(tr.meta().extra.empty());
  ASSERT_EQ(tr.size(), 2u);
  EXPECT_EQ(tr.t(), (std::vector<double>{0.0, 0.01}));
  EXPECT_EQ(tr.ticks_l(), (std::vector<std::int64_t>{0, 2}));
  EXPECT_EQ(tr.ticks_r(), (std::vector<std::int64_t>{0, 3}));
  EXPECT_EQ(tr.col(Col::gyro_z), (std::vector<double>{0.0003, 0.0011}));
  EXPECT_EQ(tr.col(Col::aps_x)[0], 0.012);
  EXPECT_EQ(tr.col(Col::aps_y)[0], -0.031);
  EXPECT_TRUE(std::isnan(tr.col(Col::aps_x)[1]));
  EXPECT_TRUE(std::isnan(tr.col(Col::aps_y)[1]));
  EXPECT_FALSE(tr.at(Col::aps_x, 1));
  EXPECT_EQ(tr.col(Col::gt_x), (std::vector<double>{0.0, 0.0001}));
  EXPECT_EQ(tr.col(Col::gt_y), (std::vector<double>{0.0, 0.0}));
  EXPECT_EQ(tr.col(Col::gt_theta), (std::vector<double>{0.0, 0.00002}));
  EXPECT_TRUE(tr.has_ticks());
  EXPECT_TRUE(tr.has_gt());
  EXPECT_TRUE(tr.has_aps());
  EXPECT_FALSE(tr.has(Col::omega_l));
  EXPECT_FALSE(tr.has(Col::v_cmd));
  EXPECT_FALSE(tr.has(Col::power_l));
}

TEST(TrackIoRead, SpecExample) { expect_spec_example(parse(kSpecExample)); }

TEST(TrackIoRead, SpecExampleFromTheSpecFile) {
  std::ifstream in(ODOTUNE_SHARED_DIR "/specs/track-format.md");
  if (!in) GTEST_SKIP() << "spec file not found";
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string spec = ss.str();
  const auto start = spec.find("```\n# format:");
  ASSERT_NE(start, std::string::npos);
  const auto end = spec.find("```", start + 3);
  ASSERT_NE(end, std::string::npos);
  expect_spec_example(parse(spec.substr(start + 4, end - start - 4), "track-format.md"));
}

TEST(TrackIoRead, UnknownMetadataKeysKeptInOrder) {
  const auto tr = parse(
      "# format: odotune-track/1\n# sim.seed: 42\n# just a comment line\n# source: logger: v2, 100 Hz\n"
      "#sim.effects:slip,bias\n# sim.seed: 43\n\nt,v_cmd,w_cmd\n0,1,2\n");
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"sim.seed", "42"}, {"source", "logger: v2, 100 Hz"}, {"sim.effects", "slip,bias"}, {"sim.seed", "43"}};
  EXPECT_EQ(tr.meta().extra, expected);
  EXPECT_EQ(tr.meta().get("source"), "logger: v2, 100 Hz");
  EXPECT_EQ(tr.meta().origin, "");
  EXPECT_FALSE(tr.meta().wheel_base_m.has_value());
}

TEST(TrackIoRead, NameDefaultsToFileStem) {
  EXPECT_EQ(parse("# format: odotune-track/1\nt,v_cmd,w_cmd\n0,1,2\n", "/data/runs/run-7.track.csv").name(),
            "run-7.track");
  EXPECT_EQ(parse("# format: odotune-track/1\n# name: given\nt,v_cmd,w_cmd\n0,1,2\n", "/x/y.csv").name(),
            "given");
}

TEST(TrackIoRead, CrlfAndBomAccepted) {
  std::string text = "\xEF\xBB\xBF" + kMeta + kHeader + "0,1,2,0.5\n0.1,,4,\n";
  std::string crlf;
  for (char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  const auto tr = parse(crlf);
  EXPECT_EQ(tr.name(), "base");
  EXPECT_EQ(tr.meta().wheel_base_m, 0.5);
  ASSERT_EQ(tr.size(), 2u);
  EXPECT_EQ(tr.t()[1], 0.1);
  EXPECT_EQ(tr.ticks_l()[1], kNoTick);
  EXPECT_EQ(tr.ticks_r()[1], 4);
  EXPECT_EQ(tr.col(Col::gyro_z)[0], 0.5);
  EXPECT_TRUE(std::isnan(tr.col(Col::gyro_z)[1]));
}

TEST(TrackIoRead, LenientLayoutAndNumberForms) {
  const auto tr = parse(
      kMeta + "\n# comment before the header\n w_cmd , t,\tticks_r ,v_cmd,ticks_l, dt, acc_x, note, x\n"
              "+1.5, 1e-3 ,+5,-0,-7,1,2,any text: here,\n"
              "# a comment row\n\n"
              "  ,.5 ,, 2.5E+2 , ,,,,\n");
  ASSERT_EQ(tr.size(), 2u);
  EXPECT_EQ(tr.t(), (std::vector<double>{1e-3, 0.5}));
  EXPECT_EQ(tr.col(Col::w_cmd)[0], 1.5);
  EXPECT_TRUE(std::isnan(tr.col(Col::w_cmd)[1]));
  EXPECT_EQ(tr.col(Col::v_cmd)[0], 0.0);
  EXPECT_TRUE(std::signbit(tr.col(Col::v_cmd)[0]));
  EXPECT_EQ(tr.col(Col::v_cmd)[1], 250.0);
  EXPECT_EQ(tr.ticks_r(), (std::vector<std::int64_t>{5, kNoTick}));
  EXPECT_EQ(tr.ticks_l(), (std::vector<std::int64_t>{-7, kNoTick}));
  // Unknown columns that do not look like known ones are ignored.
  EXPECT_FALSE(tr.has(Col::aps_x));
  EXPECT_FALSE(tr.has(Col::gyro_z));
}

TEST(TrackIoRead, UnrelatedUnknownColumnsIgnored) {
  // gyro_x / gyro_y sit beside gyro_z, so they are not taken for misspellings of it.
  for (const char* extra : {"x", "y", "dt", "id", "ts", "acc_x", "pos_x", "theta", "time_ns", "gyro_x"}) {
    SCOPED_TRACE(extra);
    const auto tr = parse(kMeta + "t,v_cmd,w_cmd,gyro_z," + extra + "\n0,1,2,3,abc\n");
    EXPECT_EQ(tr.size(), 1u);
    EXPECT_EQ(tr.col(Col::gyro_z)[0], 3.0);
  }
}

TEST(TrackIoRead, FixVariancesReadAndWrittenBack) {
  // aps_var_x, aps_var_y (the spec's table, e.g. from a NavSatFix covariance).
  const auto tr = parse(kMeta +
                        "t,v_cmd,w_cmd,aps_x,aps_y,aps_var_x,aps_var_y\n0,1,0,2.5,-1,4.0,6.25\n0.1,1,0,,,,\n");
  ASSERT_TRUE(tr.has(Col::aps_var_x));
  EXPECT_EQ(tr.col(Col::aps_var_x)[0], 4.0);
  EXPECT_EQ(tr.col(Col::aps_var_y)[0], 6.25);
  EXPECT_FALSE(tr.at(Col::aps_var_y, 1));
  std::ostringstream out;
  format_track(tr, out);
  EXPECT_NE(out.str().find("aps_x,aps_y,aps_var_x,aps_var_y"), std::string::npos) << out.str();
  const auto back = parse(out.str());
  EXPECT_EQ(back.col(Col::aps_var_y)[0], 6.25);
  // A misspelling of the new columns is caught like any other.
  EXPECT_THROW(parse(kMeta + "t,v_cmd,w_cmd,aps_vr_x\n0,1,0,1\n"), TrackError);
}

// ---------------------------------------------------------------- writes ---

// A small track with ticks, an empty cell and columns out of enum order.
Track small_track() {
  TrackData d;
  d.meta.name = "small";
  d.meta.origin = "recorded";
  d.meta.ticks_per_rev = 4096;
  d.meta.wheel_radius_left_m = 0.1;
  d.meta.wheel_radius_right_m = 0.1;
  d.meta.wheel_base_m = 0.5;
  d.meta.extra = {{"sim.seed", "7"}, {"source", "unit test"}};
  d.t = {0.0, 0.25};
  d.ticks_l = {0, kNoTick};
  d.ticks_r = {1, -2};
  d.col(Col::gt_x) = {1.5, 2.0};
  d.col(Col::gyro_z) = {std::numeric_limits<double>::quiet_NaN(), -0.125};
  return Track(std::move(d));
}

TEST(TrackIoWrite, LayoutFollowsTheSpecOrder) {
  std::ostringstream out;
  format_track(small_track(), out);
  EXPECT_EQ(out.str(),
            "# format: odotune-track/1\n# name: small\n# origin: recorded\n# robot.ticks_per_rev: 4096\n"
            "# robot.wheel_radius_left: 0.1\n# robot.wheel_radius_right: 0.1\n# robot.wheel_base: 0.5\n"
            "# sim.seed: 7\n# source: unit test\n"
            "t,ticks_l,ticks_r,gyro_z,gt_x\n0,0,1,,1.5\n0.25,,-2,-0.125,2\n");
}

TEST(TrackIoWrite, WritesAtomicallyAndLeavesNoTempFile) {
  TempDir dir;
  const fs::path target = dir.path() / "small.csv";
  {
    std::ofstream old(target);
    old << "old content\n";
  }
  write_track(small_track(), target);
  EXPECT_EQ(dir.entries(), 1u);  // the target only, no temporary
  const Track back = read_track(target);
  EXPECT_EQ(back.name(), "small");
  EXPECT_EQ(back.ticks_r(), small_track().ticks_r());
}

TEST(TrackIoWrite, MissingDirectoryFailsWithoutCreatingTarget) {
  TempDir dir;
  const fs::path target = dir.path() / "no-such-dir" / "t.csv";
  try {
    write_track(small_track(), target);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr(target.string()));
  }
  EXPECT_FALSE(fs::exists(target));
  EXPECT_FALSE(fs::exists(target.parent_path()));
  EXPECT_EQ(dir.entries(), 0u);
}

TEST(TrackIoWrite, FailedRenameRemovesTheTemporary) {
  TempDir dir;
  const fs::path target = dir.path() / "is-a-dir";
  fs::create_directories(target / "child");
  EXPECT_THROW(write_track(small_track(), target), std::runtime_error);
  EXPECT_EQ(dir.entries(), 1u);
  EXPECT_TRUE(fs::is_directory(target / "child"));
}

TEST(TrackIoWrite, RefusesTracksTheReaderWouldReject) {
  TempDir dir;
  const fs::path target = dir.path() / "bad.csv";
  TrackData d = small_track().data();
  d.meta.ticks_per_rev.reset();
  EXPECT_THROW(write_track(Track(d), target), std::runtime_error);
  d = small_track().data();
  d.meta.extra.emplace_back("robot.wheel_base", "1");
  EXPECT_THROW(write_track(Track(d), target), std::runtime_error);
  d = small_track().data();
  d.meta.extra.emplace_back("a:b", "1");
  EXPECT_THROW(write_track(Track(d), target), std::runtime_error);
  d = small_track().data();
  d.meta.name = "two\nlines";
  EXPECT_THROW(write_track(Track(d), target), std::runtime_error);
  d = small_track().data();
  d.col(Col::gt_x)[1] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(write_track(Track(d), target), std::runtime_error);
  EXPECT_EQ(dir.entries(), 0u);
  std::ostringstream out;
  EXPECT_THROW(format_track(Track(d), out), std::invalid_argument);
  EXPECT_TRUE(out.str().empty());
}

}  // namespace
}  // namespace odotune::tracks

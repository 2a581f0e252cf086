// Randomised tests of the track reader and writer (seeded, so reproducible):
// write -> read of random tracks is bit-identical, and thousands of random
// mutations of a valid file either parse or raise TrackError, nothing else.
#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <odotune/tracks/track_io.h>

namespace odotune::tracks {
namespace {

namespace fs = std::filesystem;
using Rng = std::mt19937_64;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A finite double of any magnitude: special values, random bit patterns
// (which cover subnormals and the whole exponent range) and decimal-looking
// values of random scale.
double random_finite(Rng& rng) {
  static const double kSpecial[] = {0.0,
                                    -0.0,
                                    std::numeric_limits<double>::denorm_min(),
                                    -std::numeric_limits<double>::denorm_min(),
                                    std::numeric_limits<double>::min(),
                                    std::numeric_limits<double>::max(),
                                    std::numeric_limits<double>::lowest(),
                                    std::numeric_limits<double>::epsilon(),
                                    0.1,
                                    1.0 / 3.0,
                                    1e300,
                                    -1e-300};
  switch (rng() % 4) {
    case 0: return kSpecial[rng() % std::size(kSpecial)];
    case 1:
      for (;;) {
        const double v = std::bit_cast<double>(static_cast<std::uint64_t>(rng()));
        if (std::isfinite(v)) return v;
      }
    default: {
      std::uniform_real_distribution<double> mant(-1.0, 1.0);
      std::uniform_int_distribution<int> exp10(-320, 300);
      return mant(rng) * std::pow(10.0, exp10(rng));
    }
  }
}

double random_positive(Rng& rng) {
  for (;;) {
    const double v = std::fabs(random_finite(rng));
    if (v > 0) return v;
  }
}

std::int64_t random_tick(Rng& rng) {
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  switch (rng() % 6) {
    case 0: return kNoTick;  // empty cell
    case 1: return kMax;
    case 2: return kNoTick + 1;  // the most negative count that is not "no sample"
    case 3: return static_cast<std::int64_t>(rng() % 2001) - 1000;
    default: {
      const auto v = std::bit_cast<std::int64_t>(static_cast<std::uint64_t>(rng()));
      return v == kNoTick ? kNoTick + 1 : v;
    }
  }
}

// A random track with a random subset of columns (always one odometry source)
// and all robot metadata set, `rows` rows long.
Track random_track(Rng& rng, std::size_t rows, bool all_columns) {
  TrackData d;
  d.meta.name = fmt::format("random-{}", rng() % 1000);
  d.meta.origin = rng() % 2 ? "simulated" : "";
  d.meta.ticks_per_rev = random_positive(rng);
  d.meta.wheel_radius_left_m = random_positive(rng);
  d.meta.wheel_radius_right_m = random_positive(rng);
  d.meta.wheel_base_m = random_positive(rng);
  d.meta.extra = {{"sim.seed", std::to_string(rng())}, {"sim.effects", "slip: 0.1, bias"}};
  double t = std::uniform_real_distribution<double>(-1e3, 1e3)(rng);
  for (std::size_t i = 0; i < rows; ++i) {
    d.t.push_back(t);
    switch (rng() % 3) {
      case 0: t = std::nextafter(t, std::numeric_limits<double>::infinity()); break;
      case 1: t += std::uniform_real_distribution<double>(1e-9, 1.0)(rng); break;
      default: t += std::uniform_real_distribution<double>(0.0, 1e6)(rng) + 1.0; break;
    }
  }
  const bool ticks = all_columns || rng() % 2;
  if (ticks) {
    for (std::size_t i = 0; i < rows; ++i) {
      d.ticks_l.push_back(random_tick(rng));
      d.ticks_r.push_back(random_tick(rng));
    }
  }
  for (int c = 0; c < kNumCols; ++c) {
    const bool odometry_pair = !ticks &&
                               (c == static_cast<int>(Col::v_cmd) || c == static_cast<int>(Col::w_cmd));
    if (!all_columns && !odometry_pair && rng() % 2) continue;
    auto& col = d.col(static_cast<Col>(c));
    for (std::size_t i = 0; i < rows; ++i) col.push_back(rng() % 5 == 0 ? kNaN : random_finite(rng));
  }
  return Track(std::move(d));
}

// Same numbers bit for bit (NaN matches NaN: the format has one "empty").
::testing::AssertionResult same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << "sizes " << a.size() << " vs " << b.size();
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool both_nan = std::isnan(a[i]) && std::isnan(b[i]);
    if (!both_nan && std::bit_cast<std::uint64_t>(a[i]) != std::bit_cast<std::uint64_t>(b[i]))
      return ::testing::AssertionFailure() << fmt::format("row {}: {} vs {}", i, a[i], b[i]);
  }
  return ::testing::AssertionSuccess();
}

void expect_identical(const Track& a, const Track& b) {
  EXPECT_EQ(a.name(), b.name());
  EXPECT_EQ(a.meta().origin, b.meta().origin);
  EXPECT_EQ(a.meta().extra, b.meta().extra);
  const auto opt_bits = [](const std::optional<double>& v) {
    return v ? std::bit_cast<std::uint64_t>(*v) : std::uint64_t{0};
  };
  EXPECT_EQ(opt_bits(a.meta().ticks_per_rev), opt_bits(b.meta().ticks_per_rev));
  EXPECT_EQ(opt_bits(a.meta().wheel_radius_left_m), opt_bits(b.meta().wheel_radius_left_m));
  EXPECT_EQ(opt_bits(a.meta().wheel_radius_right_m), opt_bits(b.meta().wheel_radius_right_m));
  EXPECT_EQ(opt_bits(a.meta().wheel_base_m), opt_bits(b.meta().wheel_base_m));
  EXPECT_TRUE(same_bits(a.t(), b.t()));
  EXPECT_EQ(a.ticks_l(), b.ticks_l());
  EXPECT_EQ(a.ticks_r(), b.ticks_r());
  for (int c = 0; c < kNumCols; ++c) {
    SCOPED_TRACE(column_name(static_cast<Col>(c)));
    EXPECT_EQ(a.has(static_cast<Col>(c)), b.has(static_cast<Col>(c)));
    EXPECT_TRUE(same_bits(a.col(static_cast<Col>(c)), b.col(static_cast<Col>(c))));
  }
}

TEST(TrackIoRoundTrip, RandomTracksAreBitIdentical) {
  Rng rng(20240611);
  for (int k = 0; k < 8; ++k) {
    SCOPED_TRACE(k);
    const Track original = random_track(rng, 400, k == 0);
    std::stringstream text;
    format_track(original, text);
    const Track back = parse_track(text, "random.csv");
    expect_identical(original, back);
    // The extremes of the tick range survive.
    if (k == 0) {
      EXPECT_NE(std::find(back.ticks_l().begin(), back.ticks_l().end(),
                          std::numeric_limits<std::int64_t>::max()),
                back.ticks_l().end());
      EXPECT_NE(std::find(back.ticks_r().begin(), back.ticks_r().end(), kNoTick + 1), back.ticks_r().end());
    }
  }
}

TEST(TrackIoRoundTrip, ThroughAFile) {
  Rng rng(7);
  const Track original = random_track(rng, 200, true);
  const fs::path dir = fs::temp_directory_path() / fmt::format("odotune-io-roundtrip-{}", ::getpid());
  fs::create_directories(dir);
  struct Cleanup {
    fs::path p;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
  } cleanup{dir};
  const fs::path file = dir / "rt.csv";
  write_track(original, file);
  expect_identical(original, read_track(file));
}

// A valid file exercising every feature the mutations can break.
std::string valid_file() {
  std::string s = "# format: odotune-track/1\n# name: fuzz\n# origin: recorded\n# robot.ticks_per_rev: 2048\n"
                  "# robot.wheel_radius_left: 0.1\n# robot.wheel_radius_right: 0.1\n# robot.wheel_base: 0.4\n"
                  "# sim.seed: 5\n"
                  "t,ticks_l,ticks_r,omega_l,omega_r,gyro_z,aps_x,aps_y,gt_theta,note\n";
  for (int i = 0; i < 20; ++i) {
    s += fmt::format("{},{},{},{},{},{},{},{},{},n{}\n", 0.01 * i, 3 * i, -5 * i, 0.5 + 0.01 * i, 1e-3 * i,
                     i % 3 ? std::string("2.5e-3") : std::string(), i % 4 ? "" : "1.25", i % 4 ? "" : "-3",
                     0.1 * i, i);
    if (i % 7 == 3) s += "# comment\n\n";
  }
  return s;
}

void mutate(std::string& s, Rng& rng) {
  static const char* kTokens[] = {",",
                                  "\n",
                                  "\r\n",
                                  "#",
                                  "nan",
                                  "inf",
                                  "-",
                                  "+",
                                  "1e999",
                                  ".",
                                  " ",
                                  "\0",
                                  "9223372036854775808",
                                  "\xEF\xBB\xBF",
                                  "t",
                                  "ticks_l",
                                  "gyro_zz",
                                  ",,,,"};
  const auto pos = [&] {
    return s.empty() ? std::size_t{0} : static_cast<std::size_t>(rng() % (s.size() + 1));
  };
  switch (rng() % 6) {
    case 0:  // flip a byte
      if (!s.empty()) s[rng() % s.size()] = static_cast<char>(rng() % 256);
      break;
    case 1:  // truncate
      s.resize(pos());
      break;
    case 2: {  // delete a range
      const auto p = pos();
      s.erase(p, rng() % 16);
      break;
    }
    case 3: {  // insert a token
      const char* tok = kTokens[rng() % std::size(kTokens)];
      s.insert(pos(), tok[0] == '\0' ? std::string(1, '\0') : std::string(tok));
      break;
    }
    case 4: {  // duplicate a line
      const auto p = s.rfind('\n', pos());
      const auto start = p == std::string::npos ? 0 : p + 1;
      const auto end = s.find('\n', start);
      if (end != std::string::npos) s.insert(start, s.substr(start, end - start + 1));
      break;
    }
    default:  // a random digit change keeps rows well-formed but shuffles values
      for (char& c : s)
        if (c >= '0' && c <= '9' && rng() % 50 == 0) c = static_cast<char>('0' + rng() % 10);
      break;
  }
}

// Invariants any parsed track must have.
void check_invariants(const Track& tr) {
  ASSERT_GT(tr.size(), 0u);
  EXPECT_TRUE(tr.has_odometry());
  for (std::size_t i = 0; i < tr.size(); ++i) {
    ASSERT_TRUE(std::isfinite(tr.t()[i]));
    if (i > 0) {
      ASSERT_GT(tr.t()[i], tr.t()[i - 1]);
    }
  }
  for (int c = 0; c < kNumCols; ++c)
    for (double v : tr.col(static_cast<Col>(c))) ASSERT_FALSE(std::isinf(v));
}

TEST(TrackIoRobustness, RandomMutationsParseOrRaiseTrackError) {
  Rng rng(99);
  const std::string base = valid_file();
  {
    std::istringstream in(base);
    check_invariants(parse_track(in, "base.csv"));  // the base itself is valid
  }
  const auto start = std::chrono::steady_clock::now();
  int parsed = 0, rejected = 0;
  for (int k = 0; k < 4000; ++k) {
    std::string s = base;
    const int n = 1 + static_cast<int>(rng() % 4);
    for (int m = 0; m < n; ++m) mutate(s, rng);
    if (k % 400 == 0)
      s.insert(s.size() / 2, std::string((1u << 20) + 10, k % 800 ? ',' : '7'));  // very long line
    std::istringstream in(s);
    try {
      const Track tr = parse_track(in, "fuzz.csv");
      check_invariants(tr);
      ++parsed;
    } catch (const TrackError& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "mutation " << k << " threw a non-TrackError: " << e.what();
    }
  }
  // Both outcomes occur, so the mutations are neither all fatal nor all harmless.
  EXPECT_GT(parsed, 100);
  EXPECT_GT(rejected, 100);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
}

}  // namespace
}  // namespace odotune::tracks

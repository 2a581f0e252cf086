// A run sent between MPI ranks arrives bit-identical, whatever its doubles,
// and bytes that are not exactly one run are refused, never half-read.
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include <odotune/jobs/run_record_bytes.h>

namespace odotune::cli {
namespace {

std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }

results::RunRecord awkward_record() {
  results::RunRecord r;
  r.model = "gyro";
  r.track = std::string("all-but-tr\0ack", 14) + " é";  // an embedded NUL and UTF-8
  r.heldout_track = "";
  r.mode = 6;
  r.seed = std::numeric_limits<std::uint64_t>::max();
  r.solver = "nlopt:LN_SBPLX";
  r.param_names = {"a1", "", "b2"};
  r.params = {-0.0, std::numeric_limits<double>::denorm_min(),
              std::bit_cast<double>(0x7ff8dead0000beefULL)};  // a NaN with a payload
  r.param_ranges = {
      {0.5, 2.0, true},
      {-0.0, std::numeric_limits<double>::infinity(), false},
      {std::numeric_limits<double>::denorm_min(), std::bit_cast<double>(0x7ff8dead0000beefULL), true}};
  r.best_fitness = std::numeric_limits<double>::infinity();
  r.baseline = {0.1, -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::max()};
  r.tuned = {std::nextafter(0.1, 1.0), 1e-300, std::numeric_limits<double>::quiet_NaN()};
  r.evaluations = 7550;
  r.seconds = 12.25;
  r.diverged = -3;
  r.termination = "budget";
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  for (long i = 0; i < 200; ++i) r.convergence.push_back({i * 50, u(rng)});
  return r;
}

TEST(RunRecordBytes, RoundTripKeepsEveryBit) {
  const results::RunRecord a = awkward_record();
  const results::RunRecord b = jobs::run_record_from_bytes(jobs::to_bytes(a));
  EXPECT_EQ(b.model, a.model);
  EXPECT_EQ(b.track, a.track);
  EXPECT_EQ(b.track.size(), a.track.size());
  EXPECT_EQ(b.heldout_track, a.heldout_track);
  EXPECT_EQ(b.mode, a.mode);
  EXPECT_EQ(b.seed, a.seed);
  EXPECT_EQ(b.solver, a.solver);
  EXPECT_EQ(b.param_names, a.param_names);
  ASSERT_EQ(b.params.size(), a.params.size());
  for (std::size_t i = 0; i < a.params.size(); ++i) EXPECT_EQ(bits(b.params[i]), bits(a.params[i])) << i;
  ASSERT_EQ(b.param_ranges.size(), a.param_ranges.size());
  for (std::size_t i = 0; i < a.param_ranges.size(); ++i) {
    EXPECT_EQ(bits(b.param_ranges[i].lo), bits(a.param_ranges[i].lo)) << i;
    EXPECT_EQ(bits(b.param_ranges[i].hi), bits(a.param_ranges[i].hi)) << i;
    EXPECT_EQ(b.param_ranges[i].determined, a.param_ranges[i].determined) << i;
  }
  EXPECT_EQ(bits(b.best_fitness), bits(a.best_fitness));
  for (auto [x, y] : {std::pair{&a.baseline, &b.baseline}, std::pair{&a.tuned, &b.tuned}}) {
    EXPECT_EQ(bits(y->rmse_m), bits(x->rmse_m));
    EXPECT_EQ(bits(y->mae_m), bits(x->mae_m));
    EXPECT_EQ(bits(y->maxe_m), bits(x->maxe_m));
  }
  EXPECT_EQ(b.evaluations, a.evaluations);
  EXPECT_EQ(bits(b.seconds), bits(a.seconds));
  EXPECT_EQ(b.diverged, a.diverged);
  EXPECT_EQ(b.termination, a.termination);
  ASSERT_EQ(b.convergence.size(), a.convergence.size());
  for (std::size_t i = 0; i < a.convergence.size(); ++i) {
    EXPECT_EQ(b.convergence[i].evaluations, a.convergence[i].evaluations);
    EXPECT_EQ(bits(b.convergence[i].best_fitness), bits(a.convergence[i].best_fitness));
  }
  // An empty record too.
  const results::RunRecord empty = jobs::run_record_from_bytes(jobs::to_bytes(results::RunRecord{}));
  EXPECT_TRUE(empty.params.empty());
  EXPECT_TRUE(empty.param_ranges.empty());
  EXPECT_TRUE(empty.convergence.empty());
  EXPECT_EQ(empty.solver, "pso");
}

TEST(RunRecordBytes, RefusesEveryTruncationAndTrailingOrForeignBytes) {
  const std::vector<char> whole = jobs::to_bytes(awkward_record());
  for (std::size_t n = 0; n < whole.size(); ++n)
    EXPECT_THROW(
        jobs::run_record_from_bytes(std::vector<char>(whole.begin(), whole.begin() + static_cast<long>(n))),
        std::runtime_error)
        << n << " of " << whole.size() << " bytes";
  std::vector<char> longer = whole;
  longer.push_back('x');
  EXPECT_THROW(jobs::run_record_from_bytes(longer), std::runtime_error);
  std::vector<char> foreign = whole;
  foreign[0] = static_cast<char>(foreign[0] ^ 1);
  EXPECT_THROW(jobs::run_record_from_bytes(foreign), std::runtime_error);
  // A count far beyond the bytes (a corrupt length) is refused before allocating.
  std::vector<char> huge = jobs::to_bytes(results::RunRecord{});
  const std::size_t count_at = 4 + 8 + 8 + 8 + 8 + 8 + (8 + 3);  // magic, 3 strings, mode, seed, solver
  for (std::size_t i = 0; i < 8; ++i) huge[count_at + i] = static_cast<char>(0x7f);
  EXPECT_THROW(jobs::run_record_from_bytes(huge), std::runtime_error);
  // A range's `determined` flag is one byte, 0 or 1.
  results::RunRecord ranged;
  ranged.param_names = {"q"};
  ranged.params = {1.0};
  ranged.param_ranges = {{0.5, 2.0, true}};
  std::vector<char> flag = jobs::to_bytes(ranged);
  const std::size_t flag_at = count_at + (8 + 9) + (8 + 8) + (8 + 16);  // names, params, ranges' count, lo, hi
  ASSERT_EQ(flag[flag_at], 1);
  EXPECT_TRUE(jobs::run_record_from_bytes(flag).param_ranges.at(0).determined);
  flag[flag_at] = 2;
  EXPECT_THROW(jobs::run_record_from_bytes(flag), std::runtime_error);
}

}  // namespace
}  // namespace odotune::cli

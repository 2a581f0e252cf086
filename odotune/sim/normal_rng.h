// Seeded standard normal deviates that are the same on every platform, for
// the simulator and the synthetic position fixes.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

#include <odotune/core/counter_rng.h>

namespace odotune::sim {

// SplitMix64 (Steele, Lea, Flood 2014): decorrelates the per-stream seeds.
inline std::uint64_t splitmix64(std::uint64_t x) { return core::splitmix64_mix(x); }

// Standard normal deviates: std::mt19937_64 (output fixed by the standard)
// and the Box-Muller transform written out here, because
// std::normal_distribution is implementation-defined (libstdc++ and libc++
// give different numbers for the same engine state).
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : gen_(seed) {}
  double operator()() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    constexpr double k2pow53 = 1.0 / 9007199254740992.0;                  // 2^-53
    const double u1 = static_cast<double>((gen_() >> 11) + 1) * k2pow53;  // (0, 1]
    const double u2 = static_cast<double>(gen_() >> 11) * k2pow53;        // [0, 1)
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin((2.0 * std::numbers::pi) * u2);
    has_spare_ = true;
    return r * std::cos((2.0 * std::numbers::pi) * u2);
  }

 private:
  std::mt19937_64 gen_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace odotune::sim

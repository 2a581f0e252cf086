// Branch-free elementary functions and counter-based random deviates for the
// particle calibrator's hot loop (odotune/filters/pf_calibrator.cpp).
//
// Why not <cmath> and std::normal_distribution: glibc's scalar exp/log/sin
// cost 5–8 ns each and are not vectorised without -ffast-math, which would
// dominate a particle update of a few ns; std::normal_distribution is
// stateful and implementation-defined. Everything here is plain arithmetic on
// doubles and 64-bit integers (no tables, no branches), so GCC can vectorise
// the loops that call it, and the results are the same on every platform.
//
// Accuracy (checked in tests/filters/test_pf_calibrator.cpp against <cmath>):
//   fast_log_positive: |error| < 1e-12 + 1e-15·|ln x| for normal x > 0;
//   fast_exp_nonpositive: relative error < 1e-15 for x in [−708, 0], exactly
//     0 below −708.05 (no subnormals are produced), and exp(0) = 1 exactly.
//   normal_pair_from_bits: Box–Muller (Box & Muller, "A note on the generation
//     of random normal deviates", Ann. Math. Stat. 29, 1958) on the two 32-bit
//     halves of one 64-bit hash. The radius uses 32 bits, so |z| ≤
//     √(2·33·ln 2) ≈ 6.8 (the mass beyond is < 1e-11); the angle uses 2 bits
//     for the quadrant and 30 bits within it. The log and sin/cos are
//     accurate to < 1e-12, so the deviates are N(0, 1) up to that, the
//     truncation and the 2^-32 discretisation of the radius.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

// ODOTUNE_PF_HOT_LOOP marks a particle loop that is compiled three times,
// for x86-64-v4 (AVX-512), for AVX2 and for baseline x86-64, the CPU picking
// one at load time (target_clones, an ELF ifunc). No version may contract
// a·b + c into an FMA (-ffp-contract=off, CMakeLists.txt), reductions must
// have an order fixed by the source, and everything else is elementwise IEEE
// arithmetic (floor, min and integer conversion are exact), so all versions
// give bit-identical results. Elsewhere the functions are only kept out of
// line (and, for GCC, out of interprocedural constant propagation, which
// would defeat ExpClamp). Clang (14) does not support target_clones on
// function templates, so under clang (clang-tidy parses with it; the build
// is GCC's) the loops are only kept out of line.
#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
#define ODOTUNE_PF_HOT_LOOP [[gnu::target_clones("arch=x86-64-v4", "avx2", "default")]]
#elif defined(__clang__)
#define ODOTUNE_PF_HOT_LOOP [[gnu::noinline]]
#else
#define ODOTUNE_PF_HOT_LOOP [[gnu::noipa]]
#endif

namespace odotune::filters::pf_kernels {

inline constexpr std::uint64_t kGolden = 0x9e3779b97f4a7c15ULL;  // SplitMix64's increment

// Exact conversion of an integer below 2^52 to double by building 2^52 + n in
// the bit pattern (plain integer and floating-point operations, which
// vectorise on any x86-64, unlike a 64-bit integer conversion before AVX-512).
inline double small_uint_to_double(std::uint64_t n) {
  constexpr std::uint64_t kTwo52Bits = 0x4330000000000000ULL;  // 2^52
  return std::bit_cast<double>(kTwo52Bits | n) - 4503599627370496.0;
}

// c ? a : b for plain values (constants or variables already used
// elsewhere). GCC will not if-convert, and so not vectorise, a ?: whose arm is
// a floating-point operation that might trap; so arms are kept trivial and the
// arithmetic is done outside, e.g. m·select(c, 0.5, 1.0).
inline double select(bool c, double a, double b) { return c ? a : b; }

// ln x for a normal double x > 0 (not for 0, subnormals, ∞ or NaN). x = m·2^e
// with m in [1, 2); ln m = ln 1.5 + 2·atanh(s) = ln 1.5 + 2(s + s³/3 + s⁵/5 + …),
// s = (m − 1.5)/(m + 1.5) in [−0.2, 0.143]; the series is cut after s¹⁵
// (remainder < 2·0.2¹⁷/17/(1 − 0.04) < 2e-13). No range halving, so no
// data-dependent selection in the hot loop.
inline double fast_log_positive(double x) {
  constexpr std::uint64_t kMantissa = 0x000fffffffffffffULL;
  constexpr std::uint64_t kOneBits = 0x3ff0000000000000ULL;  // 1.0
  constexpr double kLn2 = 0x1.62e42fefa39efp-1;
  constexpr double kLn1p5 = 0x1.9f323ecbf984cp-2;  // ln 1.5
  const std::uint64_t bits = std::bit_cast<std::uint64_t>(x);
  const double m = std::bit_cast<double>((bits & kMantissa) | kOneBits);  // [1, 2)
  const double e = small_uint_to_double(bits >> 52) - 1023.0;
  const double s = (m - 1.5) / (m + 1.5);
  const double z = s * s;
  double p = 2.0 / 15.0;
  p = p * z + 2.0 / 13.0;
  p = p * z + 2.0 / 11.0;
  p = p * z + 2.0 / 9.0;
  p = p * z + 2.0 / 7.0;
  p = p * z + 2.0 / 5.0;
  p = p * z + 2.0 / 3.0;
  p = p * z + 2.0;
  return e * kLn2 + (kLn1p5 + s * p);
}

// eˣ for x ≤ 0 (x = −∞ gives 0, NaN gives NaN). x = n·ln 2 + r, |r| ≤ ln2/2
// (Cody & Waite two-constant reduction), eʳ by its Taylor series to r¹³/13!
// (remainder < 0.347¹⁴/14! < 1e-17), scaled by 2ⁿ built in the exponent
// field. When n ≤ −1022 (x < −708.05) the result is exactly 0, so that no
// subnormal number (slow on x86) is ever produced.
//
// The two constants of the branch-free clamps come in an ExpClamp: a hot loop
// passes them as run-time values, because with literal constants GCC folds the
// clamped path into constants, then branches on it, and cannot vectorise.
struct ExpClamp {
  double floor = -1000.0;  // x is clamped to ≥ floor (≤ −745) so that n stays in range
  double zero = 0.0;       // must be 0.0
};

inline double fast_exp_nonpositive(double x, const ExpClamp& clamp = {}) {
  constexpr double kLog2e = 0x1.71547652b82fep+0;
  constexpr double kLn2Hi = 0x1.62e4200000000p-1;  // 20 significant bits: n·kLn2Hi exact
  constexpr double kLn2Lo = 0x1.fdf473de6af28p-22;
  constexpr double kRound = 6755399441055744.0;  // 1.5·2^52: adding it rounds to an integer
  constexpr double kTwo52 = 4503599627370496.0;
  const double xc = select(x < clamp.floor, clamp.floor, x);
  const double n = (xc * kLog2e + kRound) - kRound;
  const double r = (xc - n * kLn2Hi) - n * kLn2Lo;
  double p = 1.0 / 6227020800.0;  // 1/13!
  p = p * r + 1.0 / 479001600.0;
  p = p * r + 1.0 / 39916800.0;
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  // Biased exponent n + 1023, or 0 (giving the bit pattern of +0.0) when the
  // result would not be a normal number with room for p < 1.
  const double biased0 = n + 1023.0;
  const double biased = select(biased0 < 2.0, clamp.zero, biased0);
  const std::uint64_t e_field = std::bit_cast<std::uint64_t>(biased + kTwo52) -
                                std::bit_cast<std::uint64_t>(kTwo52);
  return p * std::bit_cast<double>(e_field << 52);
}

// sin and cos of φ for |φ| ≤ π/4 by their Taylor series to φ¹³/13! and
// φ¹²/12! (remainders < 0.786¹⁵/15! < 3e-14 and 0.786¹⁴/14! < 4e-13).
inline void sincos_quarter(double phi, double* sin_out, double* cos_out) {
  const double z = phi * phi;
  double s = 1.0 / 6227020800.0;  // 1/13!
  s = s * z - 1.0 / 39916800.0;
  s = s * z + 1.0 / 362880.0;
  s = s * z - 1.0 / 5040.0;
  s = s * z + 1.0 / 120.0;
  s = s * z - 1.0 / 6.0;
  s = s * z + 1.0;
  double c = 1.0 / 479001600.0;  // 1/12!
  c = c * z - 1.0 / 3628800.0;
  c = c * z + 1.0 / 40320.0;
  c = c * z - 1.0 / 720.0;
  c = c * z + 1.0 / 24.0;
  c = c * z - 0.5;
  *sin_out = s * phi;
  *cos_out = 1.0 + c * z;
}

// Two independent N(0, 1) deviates from 64 random bits (Box–Muller; see the
// accuracy note at the top). High 32 bits → u₁ in (0, 1), the radius
// √(−2 ln u₁); low 32 bits → the angle: bit 31 rotates by π/2, bit 30 by π,
// bits 0–29 give φ uniform in (−π/4, π/4), so the angle is uniform on the
// circle.
struct NormalPair {
  double first = 0.0;
  double second = 0.0;
};

inline NormalPair normal_pair_from_bits(std::uint64_t bits) {
  constexpr double kTwoPow32 = 0x1.0p-32;
  constexpr double kTwoPow30 = 0x1.0p-30;
  constexpr double kQuarterPi = 0x1.921fb54442d18p-1;  // π/4
  const double u1 = (small_uint_to_double(bits >> 32) + 0.5) * kTwoPow32;
  const double radius = std::sqrt(-2.0 * fast_log_positive(u1));
  const std::uint64_t low = bits & 0xffffffffULL;
  const double f = small_uint_to_double(low & 0x3fffffffULL) + 0.5;  // (0, 2^30)
  const double phi = (f * kTwoPow30 * 2.0 - 1.0) * kQuarterPi;       // (−π/4, π/4)
  double s = 0.0, c = 0.0;
  sincos_quarter(phi, &s, &c);
  // Rotation by π/2 when bit 31 is set: (c, s) → (−s, c); by π when bit 30 is
  // set: negate both. Done on the bit patterns (no branches).
  const std::uint64_t rot = 0 - (low >> 31);  // all ones or zero
  const std::uint64_t flip = ((low >> 30) & 1ULL) << 63;
  const std::uint64_t c_bits = std::bit_cast<std::uint64_t>(c);
  const std::uint64_t s_bits = std::bit_cast<std::uint64_t>(s);
  const std::uint64_t x_bits = ((s_bits ^ (1ULL << 63)) & rot) | (c_bits & ~rot);
  const std::uint64_t y_bits = (c_bits & rot) | (s_bits & ~rot);
  return {radius * std::bit_cast<double>(x_bits ^ flip), radius * std::bit_cast<double>(y_bits ^ flip)};
}

// Uniform double in (0, 1) from the high 32 bits, and from the low 32 bits, of
// 64 random bits (two independent draws from one hash).
inline double uniform_high32(std::uint64_t bits) {
  return (small_uint_to_double(bits >> 32) + 0.5) * 0x1.0p-32;
}
inline double uniform_low32(std::uint64_t bits) {
  return (small_uint_to_double(bits & 0xffffffffULL) + 0.5) * 0x1.0p-32;
}

}  // namespace odotune::filters::pf_kernels

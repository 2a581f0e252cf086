#include <odotune/filters/resampling.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <odotune/core/counter_rng.h>
#include <odotune/core/enum_names.h>
#include <odotune/filters/pf_kernels.h>

namespace odotune::filters {
namespace {

// Stream constants of counter_hash (ASCII tags), one per scheme, distinct
// from the particle calibrator's streams (pf_calibrator.cpp).
constexpr std::uint64_t kStreamMultinomial = 0x52534d554c54494eULL;  // "RSMULTIN"
constexpr std::uint64_t kStreamStratified = 0x5253535452415449ULL;   // "RSSTRATI"
constexpr std::uint64_t kStreamSystematic = 0x52535359535445ULL;     // "RSSYSTE"
constexpr std::uint64_t kStreamResidual = 0x5253524553494455ULL;     // "RSRESIDU"
constexpr std::uint64_t kGolden = 0x9e3779b97f4a7c15ULL;

// The n-th 64 random bits of the sequence keyed by `key`: SplitMix64's n-th
// output for the seed `key` (one mix per draw; the key itself comes from the
// full counter_hash of (seed, iteration, stream)).
inline std::uint64_t draw_bits(std::uint64_t key, std::uint64_t n) {
  return core::splitmix64_mix(key + n * kGolden);
}
// Uniform in the open interval (0, 1) (53 bits, never 0 or 1).
inline double open01(std::uint64_t bits) { return (static_cast<double>(bits >> 11) + 0.5) * 0x1.0p-53; }

// Buffers reused across calls (one set per thread: resample() is reentrant).
struct Scratch {
  std::vector<double> cdf;        // running sums C_i of the weights
  std::vector<int> cum;           // F_i = copies of particles 0..i
  std::vector<int> hist;          // expand: 1 + the last i with F_i = k
  std::vector<double> residual;   // residual weights (residual scheme)
  std::vector<int> residual_cum;  // cumulative multinomial copies of the residuals
  std::vector<double> uniforms;   // multinomial: the draws, their buckets,
  std::vector<int> bucket_of;
  std::vector<int> bucket_start;  // counting-sorted into equal buckets
  std::vector<double> bucket_u;
};
Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

// Running sums C_i = w_0 + … + w_i (serial, so C_{N−1} is exactly the total
// the schemes divide by). Throws when the total is not a finite number > 0.
double running_sums(std::span<const double> w, std::vector<double>* cdf) {
  cdf->resize(w.size());
  double c = 0.0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    c += w[i];
    (*cdf)[i] = c;
  }
  if (!(c > 0.0) || !std::isfinite(c))
    throw std::invalid_argument("resample: the weights must sum to a finite number > 0");
  return c;
}

// Every scheme below computes F_i = #{n : u_n ≤ C_i / T}, the number of its
// sorted points u_0 ≤ … ≤ u_{M−1} that fall at or below particle i's
// cumulative weight; ancestor(n) is then the smallest i with C_i/T ≥ u_n
// (eq. 7), i.e. #{i : F_i ≤ n}. Working with the counts F avoids the
// data-dependent branches of the classic two-pointer merge.

// Multinomial (eq. 7): M independent uniforms, counting-sorted into M equal
// buckets (expected O(N + M), no comparison sort), then F_i from the bucket
// prefix counts plus a scan of the one bucket that holds C_i/T.
// The multinomial draws: u_n and its bucket ⌊u_n M⌋ (at most M − 1). An
// ODOTUNE_PF_HOT_LOOP (pf_kernels.h): the hashes vectorise.
ODOTUNE_PF_HOT_LOOP void multinomial_draw_loop(std::uint64_t key, int m, double* __restrict u,
                                               int* __restrict bucket) {
  const double dm = static_cast<double>(m);
  for (int n = 0; n < m; ++n) {
    const double x = open01(draw_bits(key, static_cast<std::uint64_t>(n)));
    u[n] = x;
    bucket[n] = std::min(static_cast<int>(x * dm), m - 1);
  }
}

void multinomial_counts(std::span<const double> cdf, double total, std::uint64_t key, int draws, Scratch& s,
                        std::span<int> cum) {
  const std::size_t n_particles = cdf.size();
  if (draws <= 0) {
    std::fill(cum.begin(), cum.end(), 0);
    return;
  }
  const auto m = static_cast<std::size_t>(draws);
  const double dm = static_cast<double>(draws);
  s.uniforms.resize(m);
  s.bucket_of.resize(m);
  multinomial_draw_loop(key, draws, s.uniforms.data(), s.bucket_of.data());
  s.bucket_start.assign(m + 1, 0);
  for (const int b : s.bucket_of) ++s.bucket_start[static_cast<std::size_t>(b) + 1];
  for (std::size_t b = 0; b < m; ++b) s.bucket_start[b + 1] += s.bucket_start[b];
  // The draws counting-sorted by bucket, then kScan padding entries above
  // every x (so that the scan below may read past the last bucket).
  constexpr int kScan = 4;
  s.bucket_u.assign(m + kScan, 2.0);
  {
    std::vector<int>& fill = s.hist;  // next free slot of each bucket
    fill.assign(s.bucket_start.begin(), s.bucket_start.end() - 1);
    for (std::size_t n = 0; n < m; ++n)
      s.bucket_u[static_cast<std::size_t>(fill[static_cast<std::size_t>(s.bucket_of[n])]++)] = s.uniforms[n];
  }
  // F_i = (draws in buckets below x's) + #{draws in x's bucket ≤ x}. The
  // bucket is scanned kScan entries wide without a branch: entries of later
  // buckets are > x (u·M ≥ b + 1 > x·M implies u > x, rounding being
  // monotone), so reading past the bucket adds nothing; the rare bucket with
  // more than kScan draws (Poisson(1): 0.4 %) is finished by a loop.
  const double* bu = s.bucket_u.data();
  for (std::size_t i = 0; i < n_particles; ++i) {
    const double x = cdf[i] / total;
    const double xm = x * dm;
    if (!(xm < dm)) {
      cum[i] = draws;
      continue;
    }
    const auto b = static_cast<std::size_t>(xm);
    const int lo = s.bucket_start[b], hi = s.bucket_start[b + 1];
    const double* p = bu + lo;
    int count = lo + static_cast<int>(p[0] <= x) + static_cast<int>(p[1] <= x) + static_cast<int>(p[2] <= x) +
                static_cast<int>(p[3] <= x);
    for (int k = lo + kScan; k < hi; ++k) count += static_cast<int>(bu[k] <= x);
    cum[i] = count;
  }
}

// Systematic (eq. 8): u_n = (n + U)/M, so F_i = ⌊C_i M/T − U⌋ + 1. The loop
// is an ODOTUNE_PF_HOT_LOOP (pf_kernels.h): vectorised where the CPU allows,
// with identical results (the comparisons, min and int conversions are exact).
ODOTUNE_PF_HOT_LOOP void systematic_count_loop(const double* __restrict cdf, std::size_t n, double scale,
                                               double u, int m, int* __restrict cum) {
  for (std::size_t i = 0; i < n; ++i) {
    // ⌊x⌋ by truncation and a correction for negative x (x > −1 here, and
    // x < M + 1 ≤ 2^30 + 1, so the int conversion is exact): GCC does not
    // vectorise std::floor under the default -ftrapping-math.
    const double x = cdf[i] * scale - u;
    const int t = static_cast<int>(x);
    const int floor_x = t - static_cast<int>(static_cast<double>(t) > x);
    cum[i] = std::min(floor_x + 1, m);
  }
}

void systematic_counts(std::span<const double> cdf, double total, std::uint64_t key, int m,
                       std::span<int> cum) {
  const double u = open01(draw_bits(key, 0));
  systematic_count_loop(cdf.data(), cdf.size(), static_cast<double>(m) / total, u, m, cum.data());
}

// Stratified: u_n = (n + U_n)/M with an independent U_n per stratum. For
// x = C_i M/T and k = ⌊x⌋, the strata below k lie under x, and stratum k does
// iff U_k ≤ x − k: F_i = k + [U_k ≤ x − k]. An ODOTUNE_PF_HOT_LOOP, like the
// systematic one.
ODOTUNE_PF_HOT_LOOP void stratified_count_loop(const double* __restrict cdf, std::size_t n, double scale,
                                               std::uint64_t key, double dm, int* __restrict cum) {
  for (std::size_t i = 0; i < n; ++i) {
    // x ≥ 0, so ⌊x⌋ is the int truncation (std::floor does not vectorise).
    const double x = std::min(cdf[i] * scale, dm);
    const int k = static_cast<int>(x);
    const double kd = static_cast<double>(k);
    const double uk = open01(draw_bits(key, static_cast<std::uint64_t>(k)));
    cum[i] = static_cast<int>(std::min(kd + static_cast<double>(uk <= x - kd), dm));
  }
}

void stratified_counts(std::span<const double> cdf, double total, std::uint64_t key, int m,
                       std::span<int> cum) {
  stratified_count_loop(cdf.data(), cdf.size(), static_cast<double>(m) / total, key, static_cast<double>(m),
                        cum.data());
}

// Residual (eq. 9): ⌊M ρ_i⌋ copies each, then the remaining R draws
// multinomially (the classic choice; Li, Bolić & Djurić 2015, §"Residual")
// on the residuals M ρ_i − ⌊M ρ_i⌋.
void residual_counts(std::span<const double> w, double total, std::uint64_t key, int m, Scratch& s,
                     std::span<int> cum) {
  const std::size_t n_particles = w.size();
  const double scale = static_cast<double>(m) / total;
  s.residual.resize(n_particles);
  long deterministic = 0;
  for (std::size_t i = 0; i < n_particles; ++i) {
    const double x = w[i] * scale;
    const double k = std::floor(x);
    s.residual[i] = x - k;
    deterministic += static_cast<long>(k);
    cum[i] = static_cast<int>(k);  // copies for now; cumulated below
  }
  // Rounding can make Σ⌊Mρ_i⌋ exceed M by a copy in pathological cases; the
  // clamp of the cumulative counts below then trims the last ones.
  const int remainder = static_cast<int>(std::max(0L, static_cast<long>(m) - deterministic));
  s.residual_cum.resize(n_particles);
  if (remainder > 0) {
    std::vector<double>& rcdf = s.cdf;  // the weights' own running sums are no longer needed
    double rtotal = 0.0;
    rcdf.resize(n_particles);
    for (std::size_t i = 0; i < n_particles; ++i) {
      rtotal += s.residual[i];
      rcdf[i] = rtotal;
    }
    if (rtotal > 0.0) {
      multinomial_counts(rcdf, rtotal, key, remainder, s, s.residual_cum);
    } else {  // all M ρ_i integral up to rounding: the remainder goes on the weights
      double c = 0.0;
      for (std::size_t i = 0; i < n_particles; ++i) rcdf[i] = (c += w[i]);
      multinomial_counts(rcdf, c, key, remainder, s, s.residual_cum);
    }
  } else {
    std::fill(s.residual_cum.begin(), s.residual_cum.end(), 0);
  }
  long running = 0;
  for (std::size_t i = 0; i < n_particles; ++i) {
    running += cum[i];
    cum[i] = static_cast<int>(std::min(running + s.residual_cum[i], static_cast<long>(m)));
  }
}

// Every draw must land: F = M from the last particle of positive weight on
// (rounding in C_i·M/T could otherwise leave F_{N−1} one short).
void close_counts(std::span<const double> w, int m, std::span<int> cum) {
  std::size_t last = w.size() - 1;
  while (last > 0 && !(w[last] > 0.0)) --last;
  for (std::size_t i = last; i < cum.size(); ++i) cum[i] = m;
}

// ancestor(n) = #{i : F_i ≤ n}. Every scheme's F is non-decreasing (C_i is,
// and so is each scheme's count of points at or below it), so this is
// 1 + the largest i with F_i ≤ n (0 when there is none): record 1 + the
// last i of each value of F (plain stores, later i overwriting earlier), then
// carry the running maximum forward. Unlike a histogram (++hist[F_i]), the
// stores do not wait on one another when consecutive F_i are equal.
void expand(std::span<const int> cum, Scratch& s, std::span<int> out) {
  const std::size_t m = out.size();
  s.hist.assign(m + 1, 0);
  int* last = s.hist.data();
  for (std::size_t i = 0; i < cum.size(); ++i) last[cum[i]] = static_cast<int>(i) + 1;
  int running = 0;
  for (std::size_t n = 0; n < m; ++n) {
    running = std::max(running, last[n]);
    out[n] = running;
  }
}

}  // namespace

std::string_view to_string(Resampler r) {
  switch (r) {
    case Resampler::multinomial: return "multinomial";
    case Resampler::stratified: return "stratified";
    case Resampler::systematic: return "systematic";
    case Resampler::residual: return "residual";
  }
  return "?";
}

std::string_view to_string(ResamplePolicy p) {
  switch (p) {
    case ResamplePolicy::every_step: return "every";
    case ResamplePolicy::neff: return "neff";
    case ResamplePolicy::max_weight: return "max";
  }
  return "?";
}

bool parse_resampler(std::string_view text, Resampler* out) {
  return core::parse_by_name(text, kAllResamplers, out);
}

bool parse_resample_policy(std::string_view text, ResamplePolicy* out) {
  return core::parse_by_name(text, kAllResamplePolicies, out);
}

double effective_sample_size(std::span<const double> normalised_weights) {
  double sum_sq = 0.0;
  for (const double r : normalised_weights) sum_sq += r * r;
  return 1.0 / sum_sq;
}

void resample(Resampler scheme, std::span<const double> normalised_weights, std::uint64_t seed,
              std::uint64_t iteration, std::span<int> out) {
  if (out.empty()) return;
  if (normalised_weights.empty()) throw std::invalid_argument("resample: no weights to draw from");
  if (out.size() > static_cast<std::size_t>(1) << 30) throw std::invalid_argument("resample: too many draws");
  Scratch& s = scratch();
  const int m = static_cast<int>(out.size());
  const double total = running_sums(normalised_weights, &s.cdf);
  s.cum.resize(normalised_weights.size());
  switch (scheme) {
    case Resampler::multinomial:
      multinomial_counts(s.cdf, total, core::counter_hash(seed, iteration, 0, 0, kStreamMultinomial), m, s,
                         s.cum);
      break;
    case Resampler::stratified:
      stratified_counts(s.cdf, total, core::counter_hash(seed, iteration, 0, 0, kStreamStratified), m, s.cum);
      break;
    case Resampler::systematic:
      systematic_counts(s.cdf, total, core::counter_hash(seed, iteration, 0, 0, kStreamSystematic), m, s.cum);
      break;
    case Resampler::residual:
      residual_counts(normalised_weights, total, core::counter_hash(seed, iteration, 0, 0, kStreamResidual), m,
                      s, s.cum);
      break;
  }
  close_counts(normalised_weights, m, s.cum);
  expand(s.cum, s, out);
}

}  // namespace odotune::filters

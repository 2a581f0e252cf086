// Resampling for particle filters: the four schemes and three policies that
// Fariña, Toledo & Acosta (RA-L 2026, §IV.B–C, Table I) compare, after Li,
// Bolić & Djurić, "Resampling methods for particle filtering", IEEE SPM 2015.
//
// All draws come from the counter-based generator (odotune/core/counter_rng.h) keyed
// by (seed, iteration): a resampling is a pure function of its weights and
// key, so a seeded filter is reproducible whatever the thread count.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace odotune::filters {

enum class Resampler { multinomial, stratified, systematic, residual };
// When to resample (§IV.C): every iteration; when N_eff < N_th; when the
// largest normalised weight falls below a threshold.
enum class ResamplePolicy { every_step, neff, max_weight };
inline constexpr std::array<Resampler, 4> kAllResamplers = {Resampler::multinomial, Resampler::stratified,
                                                            Resampler::systematic, Resampler::residual};
inline constexpr std::array<ResamplePolicy, 3> kAllResamplePolicies = {
    ResamplePolicy::every_step, ResamplePolicy::neff, ResamplePolicy::max_weight};

std::string_view to_string(Resampler r);
std::string_view to_string(ResamplePolicy p);
// Parse "multinomial" | "stratified" | "systematic" | "residual" and
// "every" | "neff" | "max"; false (and *out untouched) for anything else.
bool parse_resampler(std::string_view text, Resampler* out);
bool parse_resample_policy(std::string_view text, ResamplePolicy* out);

// N_eff = 1 / Σ ρ_i² of normalised weights (eq. 10).
double effective_sample_size(std::span<const double> normalised_weights);

// Draws out.size() ancestor indices from the normalised weights ρ (Σρ = 1,
// ρ ≥ 0; the function divides by Σρ, so any finite weights ∝ ρ with a sum
// > 0 work too; throws std::invalid_argument for no weights or a sum that is
// not finite and > 0). out.size() may differ from ρ.size(), which is how the
// adaptive PF changes its particle count. Output indices are in increasing
// order; a particle of weight 0 is never drawn. Every scheme is unbiased:
// E[copies of i] = out.size()·ρ_i. O(N + M) time, no comparison sort; the
// draws are SplitMix64 outputs keyed by counter_hash(seed, iteration, stream).
//   multinomial: out.size() independent U(0,1] against the cumulative sum (eq. 7)
//   stratified:  one U in each stratum ((n−1)/M, n/M]
//   systematic:  one U(0, 1/M), then u_n = u_1 + (n−1)/M (eq. 8)
//   residual:    ⌊M ρ_i⌋ copies deterministically, the rest multinomially on
//                the residuals M ρ_i − ⌊M ρ_i⌋ (eq. 9; multinomial is the
//                classic choice for the remainder)
void resample(Resampler scheme, std::span<const double> normalised_weights, std::uint64_t seed,
              std::uint64_t iteration, std::span<int> out);

}  // namespace odotune::filters

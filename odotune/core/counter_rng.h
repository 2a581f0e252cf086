// Counter-based (stateless) random numbers: a uniform double is a pure hash of
// a key (seed, iteration, particle, dimension, stream). Because no generator
// state is shared or advanced, the numbers a parallel loop draws do not depend
// on which thread runs which iteration or in what order, so a seeded run is
// bit-identical for any number of threads.
//
// The hash chains the SplitMix64 finaliser (Steele, Lea & Flood, "Fast
// splittable pseudorandom number generators", OOPSLA 2014; constants as in
// S. Vigna's public-domain splitmix64.c), feeding one key word at a time. This is the "Random123" idea (Salmon et al., "Parallel random numbers:
// as easy as 1, 2, 3", SC 2011) with a cheaper, non-cryptographic mixer, which
// is ample for PSO's r1/r2 draws and the particle filter's perturbations.
//
// Lives in core/ (header-only, below every layer) because both the tuner (PSO)
// and the filters (particle-filter calibrator) draw from it, and the tracks
// layer's seeded normals (odotune/sim/normal_rng.h) use its mixer.
#pragma once

#include <cstdint>

namespace odotune::core {

// SplitMix64 output function: a bijective 64-bit mixer.
constexpr std::uint64_t splitmix64_mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// 64 random bits for the key (seed, a, b, c, stream).
constexpr std::uint64_t counter_hash(std::uint64_t seed, std::uint64_t a, std::uint64_t b, std::uint64_t c,
                                     std::uint64_t stream) {
  std::uint64_t h = splitmix64_mix(seed);
  h = splitmix64_mix(h ^ a);
  h = splitmix64_mix(h ^ b);
  h = splitmix64_mix(h ^ c);
  return splitmix64_mix(h ^ stream);
}

// Uniform double in [0, 1) with 53 random bits, for the key
// (seed, iteration, particle, dimension, stream).
constexpr double counter_uniform01(std::uint64_t seed, std::uint64_t iteration, std::uint64_t particle,
                                   std::uint64_t dimension, std::uint64_t stream) {
  const std::uint64_t bits = counter_hash(seed, iteration, particle, dimension, stream);
  return static_cast<double>(bits >> 11) * 0x1.0p-53;
}

}  // namespace odotune::core

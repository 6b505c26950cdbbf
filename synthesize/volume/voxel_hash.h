#pragma once

#include <cstdint>

namespace photomat {

// Deterministic per-voxel randomness: a value that depends only on (seed, stream, x, y, z), never
// on the order in which voxels are visited or on the thread that visits them, so solid synthesis
// gives the same bytes for a seed whatever the thread count. `stream` separates independent uses
// (pyramid level, channel, axis of a jitter vector).
//
// The mixing is SplitMix64's finaliser (Steele, Lea and Flood 2014), applied to the seed and each
// coordinate in turn; it passes BigCrush as a generator and avalanches every input bit.
inline std::uint64_t MixBits(std::uint64_t value) {
  value ^= value >> 30;
  value *= 0xbf58476d1ce4e5b9ULL;
  value ^= value >> 27;
  value *= 0x94d049bb133111ebULL;
  value ^= value >> 31;
  return value;
}

inline std::uint64_t HashVoxel(std::uint64_t seed, std::uint64_t stream, std::int64_t x,
                               std::int64_t y, std::int64_t z) {
  std::uint64_t h = MixBits(seed + 0x9e3779b97f4a7c15ULL);
  h = MixBits(h ^ (stream + 0x632be59bd9b4e019ULL));
  h = MixBits(h ^ static_cast<std::uint64_t>(x));
  h = MixBits(h ^ static_cast<std::uint64_t>(y) * 0x9e3779b97f4a7c15ULL);
  h = MixBits(h ^ static_cast<std::uint64_t>(z) * 0xc2b2ae3d27d4eb4fULL);
  return h;
}

// Uniform in [0, 1) from the top 24 bits (exact in float).
inline float HashToUnit(std::uint64_t hash) {
  return static_cast<float>(hash >> 40) * (1.0f / 16777216.0f);
}

// Uniform in [-1, 1).
inline float HashToSigned(std::uint64_t hash) { return 2.0f * HashToUnit(hash) - 1.0f; }

}  // namespace photomat

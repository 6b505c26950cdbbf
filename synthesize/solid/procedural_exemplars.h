#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "synthesize/volume/volume.h"

namespace photomat {

// Procedural solid exemplars, stand-ins for the thesis's unpublished volumes (Su 2008, section 7
// of the spec): RGB in linear [0, 1], channels "R", "G", "B", and periodic along all three axes
// (built from lattice noise and distances that wrap), so synthesis can treat them as toroidal.
enum class ProceduralPattern {
  kMarble,   // turbulent sine bands along x in two vivid colours (thesis case_1)
  kWood,     // growth rings about an axis parallel to z, with grain noise (case_8)
  kCells,    // compact cells of random colours with dark walls (case_5)
  kStripes,  // thin sheets normal to x, wobbling (case_6); the orientation tests use it
  kNoise,    // coloured fractal noise without structure
};

std::optional<ProceduralPattern> ParseProceduralPattern(std::string_view text);
std::string_view ToString(ProceduralPattern pattern);

// A size^3 exemplar (size >= 8). Same seed, same bytes.
Image MakeProceduralExemplar(ProceduralPattern pattern, int size, std::uint64_t seed);

// Periodic value noise in [-1, 1] at voxel (x, y, z) of a volume of `size`, with `cells` lattice
// cells per period, smoothly interpolated; `stream` gives independent noises.
float PeriodicNoise(double x, double y, double z, int size, int cells, std::uint64_t seed,
                    std::uint64_t stream);
// Sum of `octaves` PeriodicNoise terms, each with twice the cells and half the amplitude.
float PeriodicFractalNoise(double x, double y, double z, int size, int cells, int octaves,
                           std::uint64_t seed, std::uint64_t stream);

}  // namespace photomat

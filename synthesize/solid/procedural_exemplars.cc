#include "synthesize/solid/procedural_exemplars.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <numbers>

#include "core/enum_names.h"
#include "core/error.h"
#include "core/wrap.h"
#include "synthesize/volume/voxel_hash.h"

namespace photomat {
namespace {

using Rgb = std::array<float, 3>;

Rgb Mix(const Rgb& a, const Rgb& b, float t) {
  return {a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t};
}

float Smooth(float t) { return t * t * (3.0f - 2.0f * t); }

// Shortest distance between a and b on a circle of length `period`.
double PeriodicDelta(double a, double b, double period) {
  double d = std::fmod(std::abs(a - b), period);
  return std::min(d, period - d);
}

Rgb Marble(int x, int y, int z, int n, std::uint64_t seed) {
  const float turbulence = PeriodicFractalNoise(x, y, z, n, 4, 4, seed, 1);
  const float phase = 2.0f * std::numbers::pi_v<float> * (2.0f * x / n + 0.9f * turbulence);
  const float band = 0.5f + 0.5f * std::sin(phase);
  const Rgb deep{0.55f, 0.04f, 0.06f}, cream{0.92f, 0.86f, 0.55f}, vein{0.08f, 0.10f, 0.30f};
  Rgb colour = Mix(deep, cream, Smooth(band));
  const float vein_weight = std::max(0.0f, 1.0f - std::abs(band - 0.5f) * 12.0f);
  return Mix(colour, vein, 0.6f * vein_weight);
}

Rgb Wood(int x, int y, int z, int n, std::uint64_t seed) {
  const double centre = 0.5 * n;
  const double dx = PeriodicDelta(x, centre, n), dy = PeriodicDelta(y, centre, n);
  const float grain = PeriodicFractalNoise(x, y, z * 0.25, n, 4, 3, seed, 2);
  const double radius = std::sqrt(dx * dx + dy * dy) / n;
  const double rings = radius * 7.0 + 0.35 * grain;
  const float ring = static_cast<float>(rings - std::floor(rings));
  const float profile = Smooth(std::min(1.0f, ring * 1.6f)) * (ring < 0.85f ? 1.0f : 0.4f);
  const Rgb late{0.28f, 0.14f, 0.05f}, early{0.72f, 0.47f, 0.24f};
  const float fibre = 0.06f * PeriodicNoise(x, y, z, n, n / 2, seed, 3);
  Rgb colour = Mix(late, early, profile);
  for (float& c : colour) c = std::clamp(c + fibre, 0.0f, 1.0f);
  return colour;
}

Rgb Cells(int x, int y, int z, int n, std::uint64_t seed) {
  const int cells = std::max(2, n / 8);
  const double cell_size = static_cast<double>(n) / cells;
  const int cx = static_cast<int>(x / cell_size), cy = static_cast<int>(y / cell_size),
            cz = static_cast<int>(z / cell_size);
  double first = 1e30, second = 1e30;
  std::uint64_t nearest = 0;
  for (int oz = -1; oz <= 1; ++oz) {
    for (int oy = -1; oy <= 1; ++oy) {
      for (int ox = -1; ox <= 1; ++ox) {
        const int ix = Wrap(cx + ox, cells), iy = Wrap(cy + oy, cells), iz = Wrap(cz + oz, cells);
        const std::uint64_t id = HashVoxel(seed, 4, ix, iy, iz);
        const double px = (ix + 0.15 + 0.7 * HashToUnit(MixBits(id + 1))) * cell_size;
        const double py = (iy + 0.15 + 0.7 * HashToUnit(MixBits(id + 2))) * cell_size;
        const double pz = (iz + 0.15 + 0.7 * HashToUnit(MixBits(id + 3))) * cell_size;
        const double ddx = PeriodicDelta(x + 0.5, px, n), ddy = PeriodicDelta(y + 0.5, py, n),
                     ddz = PeriodicDelta(z + 0.5, pz, n);
        const double d = std::sqrt(ddx * ddx + ddy * ddy + ddz * ddz);
        if (d < first) {
          second = first;
          first = d;
          nearest = id;
        } else if (d < second) {
          second = d;
        }
      }
    }
  }
  const Rgb colour{0.25f + 0.7f * HashToUnit(MixBits(nearest + 11)),
                   0.25f + 0.7f * HashToUnit(MixBits(nearest + 12)),
                   0.25f + 0.7f * HashToUnit(MixBits(nearest + 13))};
  const float wall = Smooth(std::clamp(static_cast<float>((second - first) / 1.5), 0.0f, 1.0f));
  return Mix({0.03f, 0.03f, 0.04f}, colour, wall);
}

Rgb Stripes(int x, int y, int z, int n, std::uint64_t seed) {
  const float wobble = PeriodicFractalNoise(0, y, z, n, 2, 2, seed, 5);
  const float period = std::max(4.0f, n / 4.0f);
  const float phase = 2.0f * std::numbers::pi_v<float> * (x / period + 0.5f * wobble);
  const float sheet = std::pow(0.5f + 0.5f * std::cos(phase), 3.0f);
  const float speckle = 0.05f * PeriodicNoise(x, y, z, n, n / 2, seed, 6);
  return {std::clamp(0.1f + 0.8f * sheet + speckle, 0.0f, 1.0f),
          std::clamp(0.1f + 0.7f * sheet + speckle, 0.0f, 1.0f),
          std::clamp(0.15f + 0.5f * sheet + speckle, 0.0f, 1.0f)};
}

Rgb Noise(int x, int y, int z, int n, std::uint64_t seed) {
  return {0.5f + 0.45f * PeriodicFractalNoise(x, y, z, n, 4, 3, seed, 7),
          0.5f + 0.45f * PeriodicFractalNoise(x, y, z, n, 4, 3, seed, 8),
          0.5f + 0.45f * PeriodicFractalNoise(x, y, z, n, 4, 3, seed, 9)};
}

constexpr std::array<NamedValue<ProceduralPattern>, 5> kProceduralNames = {
    {{ProceduralPattern::kMarble, "marble"},
     {ProceduralPattern::kWood, "wood"},
     {ProceduralPattern::kCells, "cells"},
     {ProceduralPattern::kStripes, "stripes"},
     {ProceduralPattern::kNoise, "noise"}}};

}  // namespace

std::optional<ProceduralPattern> ParseProceduralPattern(std::string_view text) {
  return FindValueNamed(text, kProceduralNames);
}

std::string_view ToString(ProceduralPattern pattern) { return NameOf(pattern, kProceduralNames); }

float PeriodicNoise(double x, double y, double z, int size, int cells, std::uint64_t seed,
                    std::uint64_t stream) {
  cells = std::max(cells, 1);
  const double scale = static_cast<double>(cells) / size;
  const double px = x * scale, py = y * scale, pz = z * scale;
  const int ix = static_cast<int>(std::floor(px)), iy = static_cast<int>(std::floor(py)),
            iz = static_cast<int>(std::floor(pz));
  const float tx = Smooth(static_cast<float>(px - ix)), ty = Smooth(static_cast<float>(py - iy)),
              tz = Smooth(static_cast<float>(pz - iz));
  const auto lattice = [&](int dx, int dy, int dz) {
    return HashToSigned(
        HashVoxel(seed, stream, Wrap(ix + dx, cells), Wrap(iy + dy, cells), Wrap(iz + dz, cells)));
  };
  const auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
  const float x00 = lerp(lattice(0, 0, 0), lattice(1, 0, 0), tx);
  const float x10 = lerp(lattice(0, 1, 0), lattice(1, 1, 0), tx);
  const float x01 = lerp(lattice(0, 0, 1), lattice(1, 0, 1), tx);
  const float x11 = lerp(lattice(0, 1, 1), lattice(1, 1, 1), tx);
  return lerp(lerp(x00, x10, ty), lerp(x01, x11, ty), tz);
}

float PeriodicFractalNoise(double x, double y, double z, int size, int cells, int octaves,
                           std::uint64_t seed, std::uint64_t stream) {
  float sum = 0.0f, amplitude = 0.5f;
  for (int octave = 0; octave < octaves; ++octave) {
    sum += amplitude * PeriodicNoise(x, y, z, size, cells << octave, seed,
                                     stream * 16 + static_cast<std::uint64_t>(octave));
    amplitude *= 0.5f;
  }
  return sum;
}

Image MakeProceduralExemplar(ProceduralPattern pattern, int size, std::uint64_t seed) {
  if (size < 8) throw Error(fmt::format("procedural exemplar size {} is below 8", size));
  Image volume(ImageExtent::Cube(size), std::vector<std::string>{"R", "G", "B"});
  tbb::parallel_for(0, size, [&](int z) {
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) {
        Rgb colour{};
        switch (pattern) {
          case ProceduralPattern::kMarble:
            colour = Marble(x, y, z, size, seed);
            break;
          case ProceduralPattern::kWood:
            colour = Wood(x, y, z, size, seed);
            break;
          case ProceduralPattern::kCells:
            colour = Cells(x, y, z, size, seed);
            break;
          case ProceduralPattern::kStripes:
            colour = Stripes(x, y, z, size, seed);
            break;
          case ProceduralPattern::kNoise:
            colour = Noise(x, y, z, size, seed);
            break;
        }
        for (int c = 0; c < 3; ++c) volume.at(x, y, z, c) = std::clamp(colour[c], 0.0f, 1.0f);
      }
    }
  });
  return volume;
}

}  // namespace photomat

#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "core/progress.h"
#include "core/wrap.h"
#include "synthesize/volume/volume.h"

namespace photomat {

// Where exemplar coordinates may point (Su 2008, spec sections 3.1 and 4.5).
enum class ExemplarBoundary {
  kPeriodic,  // the exemplar tiles: neighbourhoods and coordinates wrap around it
  kInterior,  // it does not: only voxels whose whole neighbourhood lies inside are used, and
              // coordinates wrap within that interior box
};

struct ExemplarDomain {
  ImageExtent size;  // the exemplar array
  bool periodic = true;
  int border = 0;  // voxels left out on each face (0 when periodic)

  int origin() const { return border; }
  std::array<int, 3> extent() const {
    return {size.width - 2 * border, size.height - 2 * border, size.depth - 2 * border};
  }
  // `value` wrapped into the valid range of `axis` (the interior box, or the whole array).
  int Wrap(int value, int axis) const {
    return border + photomat::Wrap(value - border, extent()[static_cast<std::size_t>(axis)]);
  }
  bool Contains(int x, int y, int z) const {
    const auto e = extent();
    return x >= border && y >= border && z >= border && x < border + e[0] && y < border + e[1] &&
           z < border + e[2];
  }
  std::size_t Index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * size.height + y) * size.width + x;
  }
  std::array<int, 3> Coordinates(std::size_t index) const {
    const std::size_t plane = static_cast<std::size_t>(size.width) * size.height;
    return {static_cast<int>(index % size.width),
            static_cast<int>((index / size.width) % size.height), static_cast<int>(index / plane)};
  }
  // Linear indices of the valid voxels, ascending.
  std::vector<std::size_t> ValidIndices() const;
};

struct AppearanceOptions {
  int neighbourhood = 5;  // odd side of the cubic neighbourhood
  // Neighbourhood samples lie this many voxels apart: a pyramid level of spacing h matches
  // neighbourhoods spread over h times the distance, read from that level's Gaussian-stack
  // exemplar. The valid region stays the one of spacing 1, so every level shares one domain of
  // coordinates; in interior mode samples beyond the array repeat its nearest face voxel.
  int spacing = 1;
  int dimensions = 8;  // d: PCA components kept ([LH06]'s choice; the thesis gives none)
  ExemplarBoundary boundary = ExemplarBoundary::kPeriodic;
  // Volumes with more channels (map stacks: 18 PTM terms) are first reduced to this many by a
  // per-voxel PCA, so the neighbourhood vector stays small (IMPLEMENTER CHOICE).
  int max_channels = 4;
  // The feature covariance is estimated from at most this many voxels, an even stride through
  // the valid ones (IMPLEMENTER CHOICE: the basis of 375 dimensions is well determined by far
  // fewer than the 262,144 voxels of a 64^3 exemplar).
  int covariance_samples = 65536;
  // For PrepareExemplar: also build the appearance space and similarity set of every coarser
  // Gaussian-stack level that synthesis corrects (spacing 2, 4, ... while twice the spacing is
  // below the exemplar), as Lefebvre and Hoppe's pyramid synthesis does (spec section 3.3). False
  // is the thesis's single-resolution exemplar shared by all levels. IMPLEMENTER CHOICE: on by
  // default; with one shared level, coarse levels match point samples h voxels apart that say
  // little about the structure between them, correction settles on mixed, average-looking
  // exemplar regions, and the colour histogram drifts far from the exemplar's (README).
  bool gaussian_stack = true;
};

// The appearance-space exemplar (thesis section 3.1, after Lefebvre and Hoppe 2006): every valid
// exemplar voxel's neighbourhood of channel values, projected on its d principal components.
struct AppearanceSpace {
  ExemplarDomain domain;
  int neighbourhood = 5;
  int spacing = 1;
  int dimensions = 0;
  double retained_variance = 0;   // share of the feature variance the d components keep
  Eigen::VectorXf channel_mean;   // channel reduction: reduced = basis^T (value - mean)
  Eigen::MatrixXf channel_basis;  // channels x reduced channels
  Eigen::VectorXf feature_mean;   // neighbourhood^3 * reduced channels
  Eigen::MatrixXf feature_basis;  // (neighbourhood^3 * reduced channels) x d
  std::vector<float> values;      // voxel_count x d, zero outside the valid region

  std::span<const float> at(std::size_t index) const {
    return {values.data() + index * static_cast<std::size_t>(dimensions),
            static_cast<std::size_t>(dimensions)};
  }
  int reduced_channels() const { return static_cast<int>(channel_basis.cols()); }
  // The d-vector of the neighbourhood of (x, y, z) in any volume with the exemplar's channels,
  // samples `spacing` apart, wrapping around that volume (synthesised solids are toroidal).
  void Project(const Image& volume, int x, int y, int z, std::span<float> out) const;
};

// Throws Error when the exemplar is too small for the neighbourhood (and, in interior mode,
// leaves no valid voxel) or the options are out of range.
AppearanceSpace ComputeAppearanceSpace(const Image& exemplar, const AppearanceOptions& options,
                                       Progress* progress = nullptr);

}  // namespace photomat

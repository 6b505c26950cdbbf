#pragma once

#include "synthesize/volume/volume.h"

namespace photomat {

// How a filter reads beyond the faces of a volume.
enum class VolumeEdge {
  kWrap,   // the volume tiles (periodic exemplars, synthesised solids)
  kClamp,  // the nearest face voxel repeats (exemplars that do not tile)
};

// Every channel convolved with a separable Gaussian of standard deviation `sigma` voxels, the
// kernel cut at 3 sigma and normalised. sigma <= 0 returns the volume unchanged.
Image GaussianBlur(const Image& volume, double sigma, VolumeEdge edge);

// The blur of level `spacing` (a power of two) of a Gaussian stack: the standard deviation of
// log2(spacing) passes of the binomial kernel (1 4 6 4 1) / 16 of a Gaussian pyramid, each pass at
// the spacing of its level, sqrt((spacing^2 - 1) / 3); the stack keeps every voxel where the
// pyramid would subsample (Lefebvre and Hoppe 2005, section 3.1). 0 for spacing 1.
double GaussianStackSigma(int spacing);

}  // namespace photomat

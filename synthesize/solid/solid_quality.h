#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "synthesize/solid/appearance_space.h"
#include "synthesize/volume/volume.h"

namespace photomat {

// Measures of how much a synthesised solid looks like its exemplar (spec section 11 of the
// vector-field seed), for tests, benchmarks and the command's report.

// The neighbourhood-match error: the mean over output voxels p of min_u |N(p) - N_V(u)|^2, with N
// the raw neighbourhood (appearance.neighbourhood^3 voxels, all channels, wrapping around the
// solid) divided by its number of values. u is searched exactly in appearance space (PCA), and the
// distance then measured on the raw values, so the result is an upper bound of the exact minimum.
// At most `samples` voxels, drawn by a hash of `seed` (all of them when the solid is smaller).
double NeighbourhoodMatchError(const Image& solid, const Image& exemplar,
                               const AppearanceSpace& appearance, int samples = 4096,
                               std::uint64_t seed = 1);

// Mean over channels of the L1 distance between the normalised histograms of `solid` and
// `reference` on `bins` bins over the reference's range of that channel (0 to 2).
double HistogramDistance(const Image& solid, const Image& reference, int bins = 32);

// Mean over channels of the earth mover's (Wasserstein-1) distance between the value distributions
// of `solid` and `reference`, the integral of |F_solid - F_reference| over the values, in units of
// the reference's range of that channel (0 to 1). Unlike HistogramDistance it has no bins, so it
// also sees differences within a bin.
double EarthMoverDistance(const Image& solid, const Image& reference);

// Radially averaged 3D power spectrum, averaged over channels (each channel's mean removed): the
// mean |F|^2 / voxel count in `bins` rings of frequency radius (cycles per voxel) over (0, 1/2],
// comparable between volumes of different sizes. A ring holding no frequency of this size is NaN.
std::vector<double> RadialPowerSpectrum(const Image& volume, int bins = 16);
// RMS of 10 log10(a / b) over the rings both spectra have, in dB.
double LogSpectralDistance(const std::vector<double>& a, const std::vector<double>& b);

// Sum over voxels of g g^T, g the central-difference gradient (wrapping) of the channel mean.
Eigen::Matrix3d StructureTensor(const Image& volume);
// Unit eigenvector of the largest eigenvalue (the direction across stripes or sheets).
Eigen::Vector3d PrincipalDirection(const Eigen::Matrix3d& tensor);

// Share of face-adjacent voxel pairs (p, p + e) whose exemplar coordinates also differ by e
// (mod the domain): 1 for a translated copy, near 0 for noise.
double CoherentFraction(const Image& coordinates, const ExemplarDomain& domain);

// Coherent patches (spec section 11.6): the connected sets of voxels joined by coherent
// face-adjacent pairs (as above, not across the solid's faces), each a piece of the exemplar
// copied whole. A translated copy is one patch of every voxel.
struct PatchStatistics {
  int patches = 0;
  double mean_size = 0;       // voxels per patch
  double voxel_weighted = 0;  // size of the patch a voxel belongs to, averaged over voxels
  std::size_t largest = 0;
};
PatchStatistics CoherentPatches(const Image& coordinates, const ExemplarDomain& domain);

}  // namespace photomat

#pragma once

#include <vector>

#include "core/photometric_set.h"
#include "core/progress.h"

namespace photomat {

// Semi-calibrated photometric stereo: known light directions, unknown light intensities e(i, c),
// estimated jointly with the normals. For a Lambertian pixel p, I(p, i, c) = e(i, c) b(p, c).l(i),
// so with u = 1 / e the values diag(I_p) u lie in the span of the lights: the projector P_p onto
// what the pixel's lights cannot explain annihilates them. u is therefore the eigenvector of the
// smallest eigenvalue of M_c = sum_p w_p diag(I_p,c) P_p diag(I_p,c), a linear solution in the
// spirit of Cho et al. (semi-calibrated photometric stereo, TPAMI 2018), computed per channel
// (IMPLEMENTER CHOICE):
//   - each pixel uses its rank window (its darkest and brightest observations, ranked by channel
//     sum over the current intensities, are shadows and highlights) and the window's projector;
//   - iterations re-rank the windows with the new intensities and weight each pixel by a Cauchy
//     weight of the share of its corrected values the lights cannot explain (pixels that stay
//     far from Lambertian count less), until no intensity changes by more than `tolerance`.
// The scale of each channel is arbitrary (it trades against albedo): the intensities are
// normalised to a mean of 1 per channel, as a light_intensities.txt can be. With all lights
// within a cone around the camera axis, an intensity error that is a smooth function of the light
// direction (c + a.l) is only weakly observable; non-Lambertian shading shows up there first.

struct SemiCalibratedOptions {
  int max_iterations = 100;
  // Stops when no intensity changes by more than this fraction in an iteration.
  double tolerance = 1e-4;
  // Rank window of the per-pixel normal fits (as in the robust fit).
  double dark_fraction = 0.25;
  double bright_fraction = 0.1;
  // Observations with n.l below this are in attached shadow.
  double attached_shadow_cosine = 0.05;
  // At most this many of the mask's pixels take part (every k-th, deterministic): the estimate
  // is a sum over pixels, and on DiLiGenT cat 5000 give the same intensities as 20000 to 0.1 %.
  int max_pixels = 5000;
  Progress* progress = nullptr;
};

struct SemiCalibratedResult {
  // One row per image, one value per channel (mean 1 per channel).
  std::vector<std::vector<float>> intensities;
  int iterations = 0;
  double last_change = 0.0;  // largest relative change in the last iteration
};

// Estimates the intensities of `set`'s lights from its images as captured (not divided by any
// intensities). Throws Error naming the set's source for fewer than 4 images, coplanar lights, or
// too few usable pixels.
SemiCalibratedResult EstimateLightIntensities(const PhotometricSet& set,
                                              const SemiCalibratedOptions& options = {});

}  // namespace photomat

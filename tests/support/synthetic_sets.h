#pragma once

#include <vector>

#include "capture/synthetic/synthetic_capture.h"
#include "core/light_direction.h"
#include "core/photometric_set.h"

namespace photomat::testing {

// Synthetic captures with known truth, shared by the tests of several modules.
struct SyntheticSet {
  SyntheticMaterial material;
  PhotometricSet set;
};

// The thesis grid (36 lights) over a `size` x `size` material with default relief (25 degrees:
// no shadow on this grid), pure Lambertian.
SyntheticSet LambertianSet(SurfacePattern pattern = SurfacePattern::kBricks, int size = 64);

// The thesis grid over a steep material (55 degrees) with attached and cast shadows and
// Blinn-Phong highlights: what Lambertian methods cannot represent.
SyntheticSet ShadowedSpecularSet(int size = 64);

// Lights at five slants (15..75) x 12 tilts: enough distinct slants for 16-term HSH.
std::vector<LightDirection> FiveRingDome();

// Known, unequal RGB intensities for `count` lights (smooth in the light index, different per
// channel, all positive): the truth of semi-calibrated tests.
std::vector<std::vector<float>> UnequalRgbIntensities(int count);

// `set` with every image's channels multiplied by its light's `intensities` (3 channels): a
// capture under lights of those intensities, with no intensity recorded.
PhotometricSet ScaleByIntensities(const PhotometricSet& set,
                                  const std::vector<std::vector<float>>& intensities);

}  // namespace photomat::testing

#pragma once

#include <filesystem>
#include <span>
#include <vector>

#include "core/light_direction.h"
#include "core/photometric_set.h"
#include "represent/fitting/observations.h"
#include "represent/model/method.h"
#include "represent/model/representation.h"

namespace photomat {

// Fits `method` to every image of `set` over its mask (maps are 0 outside). Least squares through
// the SVD pseudo-inverse of the lighting matrix (Gradient, PTM), the three chosen images (3I), or
// the thin SVD of the image matrix through its Gram matrix (Eigen-k). Throws Error naming the
// set's source for degenerate input: fewer images than the method needs, coplanar lights
// (Gradient, 3I), lights that do not determine a biquadratic (PTM).
Representation Fit(const PhotometricSet& set, const Method& method);

// The same on prepared observations, from the images in `selected` only (leave-one-out folds).
// `lights` holds every image's light; `source` names the data in error messages.
Representation FitObservations(const Observations& observations,
                               const std::vector<LightDirection>& lights, const Method& method,
                               std::span<const int> selected,
                               const std::filesystem::path& source = {});

// The three lights 3I uses among `selected` (thesis 4.4.2, IMPLEMENTER CHOICE for other sets):
// slant 45 with tilts t, t + 90, t + 180 for the smallest tilt t where all three exist (the
// thesis's 0/90/180 first; with one of them left out, the triple rotated to the next tilt);
// otherwise the best-conditioned triple (largest |det [l1 l2 l3]|). Throws Error if every triple
// is (nearly) coplanar.
std::array<int, 3> SelectThreeImageLights(const std::vector<LightDirection>& lights,
                                          std::span<const int> selected,
                                          const std::filesystem::path& source = {});

}  // namespace photomat

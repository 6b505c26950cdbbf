#pragma once

#include "calibrate/radiometry/semi_calibrated.h"
#include "core/photometric_set.h"
#include "represent/fitting/robust_fit.h"

namespace photomat {

// Semi-calibrated light intensities (calibrate/semi_calibrated.h) whose observation weights are
// the robust fit's: at every iteration the sampled pixels, divided by the current intensities, get
// a robust Lambertian fit (robust_fit.h) and its shared outlier weights (0 for clipped samples, in
// attached shadow, small for cast shadows and highlights, near 1 for the rest) weigh each
// observation in the linear estimate. The same weights the robust normals use, so shadows and
// highlights are kept out of the intensities exactly as they are kept out of the normals.

// The weigher: `robust.measured` is ignored; clipped samples are found on the samples as captured
// (MeasuredPixelMasks with the default limits).
ObservationWeigher RobustObservationWeigher(const RobustFitOptions& robust = {});

// EstimateLightIntensities with options.weigher = RobustObservationWeigher(robust).
SemiCalibratedResult EstimateLightIntensitiesRobust(const PhotometricSet& set,
                                                    SemiCalibratedOptions options = {},
                                                    const RobustFitOptions& robust = {});

}  // namespace photomat

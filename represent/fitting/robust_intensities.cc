#include "represent/fitting/robust_intensities.h"

#include <numeric>
#include <vector>

#include "calibrate/radiometry/exposure.h"
#include "represent/fitting/observations.h"

namespace photomat {

ObservationWeigher RobustObservationWeigher(const RobustFitOptions& robust) {
  return [robust](const PhotometricSet& samples) {
    // Clipping is a property of the values as captured, before any division.
    const std::vector<Mask> measured = MeasuredPixelMasks(samples);
    PhotometricSet corrected = samples;
    corrected.ApplyIntensities();
    const Observations observations(corrected);
    std::vector<int> selected(corrected.size());
    std::iota(selected.begin(), selected.end(), 0);
    RobustFitOptions options = robust;
    options.measured = measured;
    options.progress = nullptr;
    const RobustFit fit(observations, corrected.lights(), selected, options, samples.source());
    return Eigen::MatrixXf(fit.weights());
  };
}

SemiCalibratedResult EstimateLightIntensitiesRobust(const PhotometricSet& set,
                                                    SemiCalibratedOptions options,
                                                    const RobustFitOptions& robust) {
  options.weigher = RobustObservationWeigher(robust);
  return EstimateLightIntensities(set, options);
}

}  // namespace photomat

#include "represent/fitting/robust_intensities.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "represent/fitting/fit.h"
#include "represent/model/normal_error.h"
#include "tests/support/synthetic_sets.h"

namespace photomat {
namespace {

// Per channel, the largest relative difference between two intensity tables normalised alike.
double WorstRelativeError(const std::vector<std::vector<float>>& estimate,
                          const std::vector<std::vector<float>>& truth) {
  double worst = 0.0;
  for (std::size_t c = 0; c < truth.front().size(); ++c) {
    double mean = 0.0;
    for (const auto& row : truth) mean += row[c] / static_cast<double>(truth.size());
    for (std::size_t i = 0; i < truth.size(); ++i) {
      worst = std::max(worst, std::abs(estimate[i][c] / (truth[i][c] / mean) - 1.0));
    }
  }
  return worst;
}

// A steep material with shadows and highlights under lights of known, unequal RGB intensities.
struct UnequalCapture {
  testing::SyntheticSet synthetic;
  PhotometricSet set;
  std::vector<std::vector<float>> truth;
};

UnequalCapture MakeUnequalCapture() {
  UnequalCapture capture{testing::ShadowedSpecularSet(48),
                         PhotometricSet({Image(1, 1, 3)}, {LightDirection::FromSlantTilt(0, 0)}),
                         {}};
  capture.truth = testing::UnequalRgbIntensities(capture.synthetic.set.size());
  capture.set = testing::ScaleByIntensities(capture.synthetic.set, capture.truth);
  return capture;
}

// The robust fit's weights keep the shadows and highlights out of the intensities: closer to the
// truth than the rank window's weights, and robust normals that follow the calibrated ones.
TEST(RobustIntensitiesTest, ShadowsAndHighlightsStayOutOfTheIntensities) {
  const UnequalCapture capture = MakeUnequalCapture();
  const SemiCalibratedResult window = EstimateLightIntensities(capture.set);
  const SemiCalibratedResult robust = EstimateLightIntensitiesRobust(capture.set);
  const double window_error = WorstRelativeError(window.intensities, capture.truth);
  const double robust_error = WorstRelativeError(robust.intensities, capture.truth);

  PhotometricSet calibrated = capture.set;
  calibrated.set_intensities(capture.truth);
  calibrated.ApplyIntensities();
  PhotometricSet semi = capture.set;
  semi.set_intensities(robust.intensities);
  semi.ApplyIntensities();
  const Mask all = capture.set.MaskOrAll();
  const double between =
      CompareNormals(*EstimateNormals(FitRobust(semi, Method::Parse("gradient"))),
                     *EstimateNormals(FitRobust(calibrated, Method::Parse("gradient"))), all)
          .mean_degrees;
  std::printf(
      "shadowed specular set: intensities within %.3f %% (rank window: %.3f %%, %d and %d "
      "iterations); robust normals %.3f degrees from the calibrated ones\n",
      100 * robust_error, 100 * window_error, robust.iterations, window.iterations, between);
  // Measured: 11 % worst (rank window 27 %), normals 1.6 degrees. The broad Blinn-Phong lobe
  // (shininess 30) touches most observations of this steep material and is a smooth function of
  // the light direction, the intensity error that lights within a cone barely observe; the bounds
  // guard the measured figures.
  EXPECT_LT(robust_error, 0.6 * window_error);
  EXPECT_LT(robust_error, 0.13);
  EXPECT_LT(between, 2.0);
}

// Lambertian data: both weighings give the intensities exactly.
TEST(RobustIntensitiesTest, LambertianDataGiveTheIntensitiesExactly) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 32);
  std::vector<std::vector<float>> truth;
  for (int i = 0; i < synthetic.set.size(); ++i) {
    const float gain = 0.6f + 0.02f * static_cast<float>(i);
    truth.push_back({gain, gain, gain});
  }
  const PhotometricSet set = testing::ScaleByIntensities(synthetic.set, truth);
  EXPECT_LT(WorstRelativeError(EstimateLightIntensitiesRobust(set).intensities, truth), 1e-4);
  EXPECT_LT(WorstRelativeError(EstimateLightIntensities(set).intensities, truth), 1e-4);
}

TEST(RobustIntensitiesTest, WeightsOfTheWrongShapeAreAnError) {
  const UnequalCapture capture = MakeUnequalCapture();
  SemiCalibratedOptions options;
  options.weigher = [](const PhotometricSet& samples) {
    return Eigen::MatrixXf::Ones(samples.width(), samples.size() - 1).eval();
  };
  EXPECT_THROW(EstimateLightIntensities(capture.set, options), Error);
}

}  // namespace
}  // namespace photomat

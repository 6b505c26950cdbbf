#include "calibrate/radiometry/semi_calibrated.h"

#include <gtest/gtest.h>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "tests/support/synthetic_sets.h"

namespace photomat {
namespace {

// A shadowed synthetic capture whose lights have known, unequal RGB intensities.
TEST(SemiCalibratedTest, RecoversUnequalLightIntensities) {
  SyntheticMaterialOptions material_options;
  material_options.width = material_options.height = 48;
  material_options.max_slope_degrees = 40.0;
  const SyntheticMaterial material = MakeSyntheticMaterial(material_options);
  SyntheticRenderOptions render;
  render.shadows = true;
  const PhotometricSet equal = RenderSyntheticCapture(material, ThesisLightGrid(), render);
  const std::vector<std::vector<float>> truth = testing::UnequalRgbIntensities(equal.size());
  const PhotometricSet set = testing::ScaleByIntensities(equal, truth);
  const SemiCalibratedResult result = EstimateLightIntensities(set);
  ASSERT_EQ(result.intensities.size(), truth.size());
  for (int c = 0; c < 3; ++c) {
    double mean = 0.0;
    for (const auto& row : truth) mean += row[c] / static_cast<double>(truth.size());
    for (std::size_t i = 0; i < truth.size(); ++i) {
      EXPECT_NEAR(result.intensities[i][c], truth[i][c] / mean, 0.002) << "image " << i;
    }
  }
}

TEST(SemiCalibratedTest, RejectsTooFewImagesAndCoplanarLights) {
  const PhotometricSet three(
      std::vector<Image>(3, Image(8, 8, 3)),
      {LightDirection::FromSlantTilt(30, 0), LightDirection::FromSlantTilt(30, 120),
       LightDirection::FromSlantTilt(30, 240)});
  EXPECT_THROW(EstimateLightIntensities(three), Error);
  std::vector<LightDirection> ring;
  for (int k = 0; k < 6; ++k) ring.push_back(LightDirection::FromSlantTilt(90, 60.0 * k));
  const PhotometricSet coplanar(std::vector<Image>(6, Image(8, 8, 3)), ring);
  EXPECT_THROW(EstimateLightIntensities(coplanar), Error);
}

}  // namespace
}  // namespace photomat

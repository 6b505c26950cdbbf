#include "calibrate/radiometry/semi_calibrated.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

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

// A capture too large to hold is estimated from its sampled pixels gathered band by band: bands
// of 5 rows, added in reverse order, give the samples of the whole set and the same intensities
// bit for bit; with a mask too.
TEST(SemiCalibratedTest, SamplesGatheredBandByBandGiveTheWholeSetsIntensities) {
  SyntheticMaterialOptions material_options;
  material_options.width = 40;
  material_options.height = 33;
  const SyntheticMaterial material = MakeSyntheticMaterial(material_options);
  SyntheticRenderOptions render;
  render.shadows = true;
  PhotometricSet set =
      testing::ScaleByIntensities(RenderSyntheticCapture(material, ThesisLightGrid(), render),
                                  testing::UnequalRgbIntensities(36));
  SemiCalibratedOptions options;
  options.max_pixels = 300;  // every 5th pixel: samples in every band
  for (const bool masked : {false, true}) {
    if (masked) {
      Mask mask(set.width(), set.height(), false);
      for (int y = 4; y < 30; ++y) {
        for (int x = 3 + y % 4; x < 37; ++x) mask.Set(x, y, true);
      }
      set.set_mask(mask);
    }
    SemiCalibratedSamples samples(SemiCalibratedPixels(set.MaskOrAll(), options), set.width());
    for (int first = (set.height() - 1) / 5 * 5; first >= 0; first -= 5) {
      const int rows = std::min(5, set.height() - first);
      std::vector<Image> band;
      for (const Image& image : set.images()) band.emplace_back(image.Rows(first, rows));
      samples.Add(PhotometricSet(std::move(band), set.lights(), set.image_names(), set.source()),
                  first);
    }
    const SemiCalibratedResult whole = EstimateLightIntensities(set, options);
    const SemiCalibratedResult banded =
        EstimateLightIntensitiesFromSamples(samples.samples(), options);
    EXPECT_EQ(banded.intensities, whole.intensities) << (masked ? "masked" : "whole frame");
    EXPECT_EQ(banded.iterations, whole.iterations);
    EXPECT_GT(whole.iterations, 1);
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

#include "tests/support/synthetic_sets.h"

#include <cmath>
#include <utility>

namespace photomat::testing {

SyntheticSet LambertianSet(SurfacePattern pattern, int size) {
  SyntheticMaterialOptions options;
  options.pattern = pattern;
  options.width = options.height = size;
  SyntheticMaterial material = MakeSyntheticMaterial(options);
  PhotometricSet set = RenderSyntheticCapture(material, ThesisLightGrid());
  return {std::move(material), std::move(set)};
}

SyntheticSet ShadowedSpecularSet(int size) {
  SyntheticMaterialOptions options;
  options.pattern = SurfacePattern::kBricks;
  options.width = options.height = size;
  options.max_slope_degrees = 55.0;
  SyntheticMaterial material = MakeSyntheticMaterial(options);
  SyntheticRenderOptions render;
  render.shadows = true;
  render.specular = 0.4;
  render.shininess = 30.0;
  PhotometricSet set = RenderSyntheticCapture(material, ThesisLightGrid(), render);
  return {std::move(material), std::move(set)};
}

std::vector<LightDirection> FiveRingDome() {
  std::vector<LightDirection> lights;
  for (int slant = 15; slant <= 75; slant += 15) {
    for (int tilt = 0; tilt < 360; tilt += 30) {
      lights.push_back(LightDirection::FromSlantTilt(slant, tilt + slant));
    }
  }
  return lights;
}

std::vector<std::vector<float>> UnequalRgbIntensities(int count) {
  std::vector<std::vector<float>> intensities;
  for (int i = 0; i < count; ++i) {
    intensities.push_back({1.0f + 0.4f * std::sin(1.3f * i), 0.8f + 0.05f * (i % 5),
                           1.2f - 0.3f * std::cos(0.7f * i)});
  }
  return intensities;
}

PhotometricSet ScaleByIntensities(const PhotometricSet& set,
                                  const std::vector<std::vector<float>>& intensities) {
  std::vector<Image> images;
  for (int i = 0; i < set.size(); ++i) {
    Image image = set.image(i);
    for (std::size_t p = 0; p < image.pixel_count(); ++p) {
      for (int c = 0; c < 3; ++c) image.pixel(p)[c] *= intensities[i][c];
    }
    images.push_back(std::move(image));
  }
  return PhotometricSet(std::move(images), set.lights());
}

}  // namespace photomat::testing

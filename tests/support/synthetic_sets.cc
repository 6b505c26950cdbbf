#include "tests/support/synthetic_sets.h"

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

}  // namespace photomat::testing

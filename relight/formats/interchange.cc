#include "relight/formats/interchange.h"

#include <tbb/parallel_for.h>

#include "core/colour.h"
#include "core/error.h"
#include "relight/formats/stack_file.h"
#include "represent/fitting/fit.h"

namespace photomat {
namespace {

void EncodeSrgb(Image& image) {
  for (float& v : image.values()) v = static_cast<float>(LinearToSrgb(v));
}

}  // namespace

Representation FitEncoded(const PhotometricSet& set, const Method& method) {
  std::vector<Image> encoded = set.images();
  tbb::parallel_for(std::size_t{0}, encoded.size(), [&](std::size_t i) { EncodeSrgb(encoded[i]); });
  PhotometricSet copy(std::move(encoded), set.lights(), set.image_names(), set.source());
  if (set.mask()) copy.set_mask(*set.mask());
  return Fit(copy, method);
}

std::vector<LightDirection> RefitLights() {
  std::vector<LightDirection> lights = {LightDirection::FromSlantTilt(0, 0)};
  for (int slant = 10; slant <= 80; slant += 10) {
    for (int tilt = 0; tilt < 360; tilt += 15) {
      lights.push_back(LightDirection::FromSlantTilt(slant, tilt));
    }
  }
  return lights;
}

Representation ConvertToEncoded(const LoadedStack& stack, const Method& method) {
  const Representation& source = stack.representation;
  const bool encoded = StackValueEncoding(stack.provenance) == ColourSpace::kSrgb;
  if (encoded && source.method() == method.Name()) return source;
  const auto refit = [&](const std::vector<LightDirection>& lights) {
    std::vector<Image> images(lights.size());
    tbb::parallel_for(std::size_t{0}, lights.size(), [&](std::size_t i) {
      images[i] = source.Relight(lights[i]);
      if (!encoded) EncodeSrgb(images[i]);
    });
    return Fit(PhotometricSet(std::move(images), lights, {}, stack.provenance.source), method);
  };
  const auto& captured = stack.provenance.capture_lights;
  if (captured.size() >= static_cast<std::size_t>(method.MinimumImages())) {
    try {
      return refit(captured);
    } catch (const Error&) {
      // The capture's lights do not determine `method` (one ring of lights for PTM, three slants
      // for hsh16): sample the representation on the dome instead.
    }
  }
  return refit(RefitLights());
}

}  // namespace photomat

#include "synthesize/texture/integrable_projection.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>

#include "core/error.h"
#include "represent/surface/surface_integration.h"

namespace photomat {
namespace {

constexpr std::array<const char*, 3> kNormalMaps = {"normal.X", "normal.Y", "normal.Z"};

std::array<int, 3> NormalChannels(const Representation& representation) {
  std::array<int, 3> channels{};
  for (int i = 0; i < 3; ++i) channels[i] = representation.maps().FindChannel(kNormalMaps[i]);
  return channels;
}

Image NormalMaps(const Representation& representation) {
  const std::array<int, 3> channels = NormalChannels(representation);
  const Image& maps = representation.maps();
  Image normals(maps.width(), maps.height(),
                std::vector<std::string>(kNormalMaps.begin(), kNormalMaps.end()));
  for (int k = 0; k < 3; ++k) {
    std::copy(maps.plane(channels[k]).begin(), maps.plane(channels[k]).end(),
              normals.plane(k).begin());
  }
  return normals;
}

}  // namespace

bool HasNormalMaps(const Representation& representation) {
  for (int channel : NormalChannels(representation)) {
    if (channel < 0) return false;
  }
  return true;
}

Representation ProjectNormalsToIntegrable(const Representation& representation) {
  if (!HasNormalMaps(representation)) {
    throw Error(
        fmt::format("{}: the integrable projection needs normal maps (normal.X, normal.Y, "
                    "normal.Z: a gradient stack)",
                    representation.method()));
  }
  const Image projected =
      NormalsFromGradients(ProjectToIntegrable(GradientsFromNormals(NormalMaps(representation))));
  Image maps = representation.maps();
  const std::array<int, 3> channels = NormalChannels(representation);
  for (int k = 0; k < 3; ++k) {
    std::copy(projected.plane(k).begin(), projected.plane(k).end(),
              maps.plane(channels[k]).begin());
  }
  nlohmann::json details = representation.details();
  if (!details.is_object()) details = nlohmann::json::object();
  details["integrable_projection"] = true;
  return representation.WithMapsAndDetails(std::move(maps), std::move(details));
}

Image HeightFromRepresentation(const Representation& representation) {
  if (HasNormalMaps(representation)) {
    return IntegrateFrankotChellappa(GradientsFromNormals(NormalMaps(representation)));
  }
  const std::optional<Image> normals = EstimateNormals(representation);
  if (!normals) {
    throw Error(fmt::format("{}: this representation gives no normals to integrate into a height",
                            representation.method()));
  }
  return IntegrateFrankotChellappa(GradientsFromNormals(*normals));
}

}  // namespace photomat

#include "represent/model/shading.h"

#include <fmt/format.h>

#include "core/microfacet_brdf.h"
#include "represent/model/neural_decoder.h"

namespace photomat {

std::vector<std::string> MicrofacetShading::MapNames() const {
  return {"base.R", "base.G", "base.B", "roughness", "f0", "normal.X", "normal.Y", "normal.Z"};
}

void MicrofacetShading::Shade(PixelValues<const float> maps, std::span<const float> light,
                              std::span<float> out) const {
  const float normal[3] = {maps[kNormal], maps[kNormal + 1], maps[kNormal + 2]};
  const MicrofacetResponse<float> response =
      MicrofacetRadiance(normal, light.data(), maps[kRoughness], maps[kF0]);
  for (int c = 0; c < 3; ++c) out[c] = response.diffuse * maps[kBase + c] + response.specular;
}

std::shared_ptr<const PixelShading> PixelShadingFromJson(const JsonReader& json) {
  const std::string kind = json["kind"].String();
  if (kind == "microfacet") return std::make_shared<MicrofacetShading>();
  if (kind == "neural") {
    return std::make_shared<NeuralShading>(NeuralDecoder::FromJson(json["decoder"]));
  }
  json["kind"].Fail(
      fmt::format("unknown shading \"{}\": expected \"microfacet\" or \"neural\"", kind));
}

}  // namespace photomat

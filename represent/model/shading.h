#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/image.h"
#include "core/json_file.h"

namespace photomat {

// A per-pixel nonlinear shading: the output channels of one pixel from its maps and the light.
// For models that are not linear in their maps (the `pbr` method's microfacet BRDF), which the
// linear gain * sum_j c_j B_j of MapLayout cannot express. A Representation that has one relights
// through it, with its light basis (DirectionLightBasis) giving the light direction as the
// coefficients, so that every caller of Coefficients() + RelightPixel() works on it unchanged.
class PixelShading {
 public:
  virtual ~PixelShading() = default;
  virtual std::string_view kind() const = 0;
  virtual int map_count() const = 0;
  virtual int output_channels() const = 0;
  // Names of the maps, in order (the stack's layer names).
  virtual std::vector<std::string> MapNames() const = 0;
  // The first of the three maps holding the unit normal; nullopt for a shading without normal
  // maps (the `neural` basis's learned coefficients).
  virtual std::optional<int> normal_offset() const = 0;
  // `light` is the unit direction towards the light (3 values).
  virtual void Shade(PixelValues<const float> maps, std::span<const float> light,
                     std::span<float> out) const = 0;
  // {"kind": ...}; read back by PixelShadingFromJson.
  virtual nlohmann::json ToJson() const = 0;
};

// The `pbr` maps and their shading: core/microfacet_brdf.h (diffuse + GGX, Smith
// height-correlated, Schlick; glTF conventions) with maps base.R, base.G, base.B (base colour),
// roughness (perceptual, alpha = roughness^2), f0 (grey Fresnel reflectance at normal incidence),
// normal.X, normal.Y, normal.Z. RGB output.
class MicrofacetShading final : public PixelShading {
 public:
  static constexpr int kBase = 0;
  static constexpr int kRoughness = 3;
  static constexpr int kF0 = 4;
  static constexpr int kNormal = 5;
  static constexpr int kMapCount = 8;

  std::string_view kind() const override { return "microfacet"; }
  int map_count() const override { return kMapCount; }
  int output_channels() const override { return 3; }
  std::vector<std::string> MapNames() const override;
  std::optional<int> normal_offset() const override { return kNormal; }
  void Shade(PixelValues<const float> maps, std::span<const float> light,
             std::span<float> out) const override;
  nlohmann::json ToJson() const override { return {{"kind", "microfacet"}}; }
};

// Whether `shading` is the `pbr` method's (its maps are base colour, roughness, F0 and a normal).
inline bool IsMicrofacet(const PixelShading* shading) {
  return shading && shading->kind() == "microfacet";
}

// "microfacet" or "neural" (represent/model/neural_decoder.h). Throws Error naming the reader's
// file and JSON path for unknown kinds or a malformed decoder.
std::shared_ptr<const PixelShading> PixelShadingFromJson(const JsonReader& json);

}  // namespace photomat

#pragma once

#include <Eigen/Core>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/light_direction.h"
#include "represent/model/light_basis.h"
#include "represent/model/shading.h"

namespace photomat {

// How a representation's n maps combine with the k light coefficients c(l) into C output
// channels. Every method of the thesis (and PTM LRGB, HSH, ...) is one instance of
//
//   out_o = gain_o * sum_j c_j * B_j,o
//
// where the basis maps B_j,o are per output channel (3I images, PTM RGB, Eigen-k bases) or shared
// by all channels (Gradient's normal, LRGB's luminance polynomial: B_j,o = B_j), and the gain maps
// (Gradient's albedo, LRGB's chroma) are optional (gain = 1 without). Map order: basis maps
// j-major (j * B + b, B = C or 1), then the C gain maps.
struct MapLayout {
  int basis_size = 0;             // k
  bool basis_per_channel = true;  // B_j,o per output channel, or one B_j shared
  bool has_gain = false;          // C gain maps follow the basis maps
  int output_channels = 0;        // C
  // > 0: a nonlinear per-pixel shading (represent/model/shading.h) of this many maps replaces the
  // linear sum; the basis then gives the shading its light input (k = 3, the direction).
  int shading_maps = 0;

  int BasisMapsPerTerm() const { return basis_per_channel ? output_channels : 1; }
  int MapCount() const {
    if (shading_maps > 0) return shading_maps;
    return basis_size * BasisMapsPerTerm() + (has_gain ? output_channels : 0);
  }
  int GainOffset() const { return basis_size * BasisMapsPerTerm(); }
  nlohmann::json ToJson() const;
};

struct RelightOptions {
  // Clamp negative results to 0 (attached shadow). Off by default: the thesis's linear model.
  bool clamp_negative = false;
};

// A relightable representation: n float maps (an Image with named channels: the pixels' n-vectors
// travel together through synthesis) plus the light basis that turns a light into coefficients.
// Synthesis, relighting and export work on every method alike through this type.
class Representation {
 public:
  // Throws Error if the maps do not have layout.MapCount() channels or the basis size differs.
  Representation(std::string method, Image maps, MapLayout layout,
                 std::shared_ptr<const LightBasis> basis, nlohmann::json details = {});
  // A nonlinear per-pixel shading (the `pbr` method): the layout follows from it (shading_maps,
  // its output channels) and the basis is the light direction (DirectionLightBasis).
  Representation(std::string method, Image maps, std::shared_ptr<const PixelShading> shading,
                 nlohmann::json details = {});

  // "3i", "gradient", "ptm", "ptm-lrgb", "eigen3", ...
  const std::string& method() const { return method_; }
  const Image& maps() const { return maps_; }
  const MapLayout& layout() const { return layout_; }
  const LightBasis& basis() const { return *basis_; }
  std::shared_ptr<const LightBasis> shared_basis() const { return basis_; }
  // The nonlinear shading, or null for the linear methods (every method but `pbr`).
  const PixelShading* shading() const { return shading_.get(); }
  std::shared_ptr<const PixelShading> shared_shading() const { return shading_; }
  // Method-specific facts of the fit (singular values, the images 3I used, ...).
  const nlohmann::json& details() const { return details_; }
  int width() const { return maps_.width(); }
  int height() const { return maps_.height(); }
  int output_channels() const { return layout_.output_channels; }

  // The image under `light` (output channels named R, G, B or Y).
  Image Relight(const LightDirection& light, const RelightOptions& options = {}) const;
  // One pixel: `maps` is the pixel's n-vector, `coefficients` = basis().Coefficients(light).
  void RelightPixel(PixelValues<const float> maps, const Eigen::VectorXf& coefficients,
                    std::span<float> out) const;

  // The same method and light basis (and shading) over other maps of the same layout (a
  // synthesised texture), and with other details.
  Representation WithMaps(Image maps) const;
  Representation WithMapsAndDetails(Image maps, nlohmann::json details) const;

 private:
  std::string method_;
  Image maps_;
  MapLayout layout_;
  std::shared_ptr<const LightBasis> basis_;
  nlohmann::json details_;
  std::shared_ptr<const PixelShading> shading_;
};

// Names of C output channels: "Y" for 1, "R","G","B" for 3, "C0".. otherwise.
std::vector<std::string> OutputChannelNames(int channels);

// Names of per-channel coefficient maps, term-major: "<prefix><j>.<channel>" for j < terms (e.g.
// "ptm.a0.R", "ptm.a0.G", ...), the order the fitters store and the map stacks name layers by.
std::vector<std::string> CoefficientMapNames(const std::string& prefix, int terms,
                                             const std::vector<std::string>& channel_names);

// Unit normals (3 channels "normal.X/Y/Z") where the method defines them: any representation whose
// light basis is linear in l (Gradient, 3I: the albedo-scaled normal is sum_j A_j B_j,o, summed
// over channels), PTM (the light direction of maximal luminance, Malzbender et al. 2001) and a
// shading's normal maps (pbr). nullopt for others (Eigen-k).
std::optional<Image> EstimateNormals(const Representation& representation);

}  // namespace photomat

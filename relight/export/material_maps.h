#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "core/colour.h"
#include "core/image.h"
#include "core/light_direction.h"
#include "represent/model/representation.h"

namespace photomat {

// The maps graphics tools take (normals, albedo, height), derived from any representation.

enum class HeightIntegrator {
  kPoisson,           // masked least squares: non-periodic samples (the default)
  kFrankotChellappa,  // FFT, periodic: tileable samples
};
std::string_view ToString(HeightIntegrator integrator);  // "poisson", "fc"
// "poisson", "fc" or "frankot-chellappa"; throws Error otherwise.
HeightIntegrator ParseHeightIntegrator(std::string_view name);

struct MaterialMaps {
  Image normals;  // unit normals "normal.X/Y/Z" in the light frame; 0 outside `mask`
  Image albedo;   // linear, "albedo.R/G/B" (or "albedo.Y"); 0 outside `mask`
  Image height;   // "height", in pixel units; zero mean over `mask`, 0 outside (Poisson)
  Mask mask;      // the pixels the representation covers
  std::string normals_source;  // how the normals were obtained (for export.json)
};

struct MaterialMapOptions {
  HeightIntegrator height = HeightIntegrator::kPoisson;
  // How the representation's relit values encode light (kSrgb for .ptm/.rti files).
  ColourSpace values = ColourSpace::kLinear;
  // Where the representation was fitted (its capture lights); used to sample it when normals must
  // be estimated from relit images. Empty: a dome of lights.
  std::vector<LightDirection> sample_lights;
};

// The pixels whose maps are not all zero (fits leave maps at 0 outside their mask).
Mask CoverageMask(const Representation& representation);

// Normals and albedo (IMPLEMENTER CHOICE, in this order of preference):
//   1. the representation's own "normal.*" and "albedo.*" maps (Gradient);
//   2. normals from EstimateNormals (bases linear in the light: 3I; PTM's luminance maximum);
//   3. otherwise (Eigen-k, HSH) least-squares Lambertian normals of the representation relit at
//      the sample lights (the capture's, or a dome when they are coplanar or unknown).
// In 2 and 3 the albedo of each channel is the Lambertian one along the normal, from the same
// relit images (photometric stereo on the representation itself). sRGB-encoded values are decoded
// to linear first. Height integrates the normals' gradients with `options.height` over the mask.
MaterialMaps ExtractMaterialMaps(const Representation& representation,
                                 const MaterialMapOptions& options = {});

// The per-pixel part of ExtractMaterialMaps: mask, normals, albedo and their source, without the
// height (left empty). Each pixel's maps depend on its own maps only, so a band of a stack gives
// the rows of the whole stack's maps (streamed export). Unlike ExtractMaterialMaps, a band whose
// maps are all zero is not an error (its normals and albedo are 0).
MaterialMaps ExtractSurfaceMaps(const Representation& representation,
                                const MaterialMapOptions& options = {});

// Height (pixel units) from unit normals by `integrator`; Poisson over `mask` (all if empty).
Image HeightFromNormals(const Image& normals, const Mask& mask, HeightIntegrator integrator);

}  // namespace photomat

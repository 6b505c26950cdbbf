#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "capture/io/capture_manifest.h"
#include "core/image.h"
#include "core/light_direction.h"
#include "core/photometric_set.h"

namespace photomat {

// A synthetic capture with ground truth: a procedural material (a height field and an RGB albedo)
// rendered orthographically under known distant lights. Tests fit it and compare with the truth;
// `photomat generate` and `photomat demo` write it as a set any subcommand reads.

enum class SurfacePattern {
  kBumps,    // scattered round bumps and dents over a mottled albedo
  kGrooves,  // parallel grooves with a gentle cross undulation, striped albedo
  kBricks,   // bevelled bricks in running bond, per-brick colour and tilt, mortar joints
};
std::string_view ToString(SurfacePattern pattern);
std::optional<SurfacePattern> ParseSurfacePattern(std::string_view name);

struct SyntheticMaterialOptions {
  SurfacePattern pattern = SurfacePattern::kBricks;
  int width = 128;
  int height = 128;
  // The steepest surface slope, in degrees. The default 25 keeps every normal within 25 degrees
  // of +z, so n.l > 0 for every light up to slant 65: the thesis grid (slants <= 60) then has no
  // attached or cast shadow and the Lambertian images are exact. Steeper relief (e.g. 55) makes
  // shadows.
  double max_slope_degrees = 25.0;
  std::uint64_t seed = 1;
  // The GGX maps (SyntheticMaterial::roughness, ::f0): smooth periodic fields spanning
  // [min, max], drawn from their own stream of `seed` (the height and albedo do not change).
  double roughness_min = 0.35;
  double roughness_max = 0.65;
  double f0_min = 0.04;
  double f0_max = 0.08;
};

// The truth, sampled at pixel centres; periodic in x and y (the sample tiles seamlessly).
struct SyntheticMaterial {
  Image height;     // 1 channel "height", in pixel units (x right, y up)
  Image normals;    // 3 channels "R","G","B" = unit normal x, y, z (as DiLiGenT's gt_normals.exr)
  Image albedo;     // 3 channels linear RGB in [0.05, 0.9]; the base colour of the GGX material
  Image roughness;  // 1 channel "roughness": perceptual roughness (GGX alpha = roughness^2)
  Image f0;         // 1 channel "f0": grey Fresnel reflectance at normal incidence
};

SyntheticMaterial MakeSyntheticMaterial(const SyntheticMaterialOptions& options);

struct SyntheticRenderOptions {
  // Attached shadows (max(0, n.l)) and cast shadows (ray marching over the periodic height
  // field). Off: the pure linear model albedo * n.l, negative where n.l < 0, which is exact for
  // the Lambertian methods (integer image files clamp negatives to 0).
  bool shadows = false;
  // Blinn-Phong specular coefficient k_s (white highlights); 0 is Lambertian.
  double specular = 0.0;
  // The GGX material instead (core/microfacet_brdf.h, the model `pbr` fits): base colour =
  // albedo, the material's roughness and F0 maps. Excludes `specular`.
  bool microfacet = false;
  double shininess = 40.0;
  // Standard deviation of additive Gaussian noise, in units of full scale (1.0).
  double noise_sigma = 0.0;
  std::uint64_t noise_seed = 1;
};

// One linear RGB image per light; each light has intensity 1.
PhotometricSet RenderSyntheticCapture(const SyntheticMaterial& material,
                                      const std::vector<LightDirection>& lights,
                                      const SyntheticRenderOptions& options = {});

// Writes the set (images, manifest.json) and the truth (gt_normals.exr, gt_albedo.exr,
// gt_height.exr, referenced from the manifest; gt_roughness.exr and gt_f0.exr beside them) into
// `folder`.
void WriteSyntheticCapture(const std::filesystem::path& folder, const SyntheticMaterial& material,
                           const PhotometricSet& set, const SaveSetOptions& options = {});

}  // namespace photomat

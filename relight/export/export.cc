#include "relight/export/export.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/export/gltf_tile.h"
#include "relight/formats/stack_file.h"
#include "represent/model/shading.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

struct Range {
  double low = 0.0, high = 0.0;
};

Range HeightRange(const Image& height, const Mask& mask) {
  Range range{INFINITY, -INFINITY};
  for (std::size_t p = 0; p < height.pixel_count(); ++p) {
    if (!mask[p]) continue;
    range.low = std::min(range.low, double{height.pixel(p)[0]});
    range.high = std::max(range.high, double{height.pixel(p)[0]});
  }
  return range;
}

// Height mapped to [0, 1] over its range (0.5 for a flat surface), 0 outside the mask.
Image NormalisedHeight(const Image& height, const Mask& mask, const Range& range) {
  Image out(height.width(), height.height(), 1);
  const double span = range.high - range.low;
  for (std::size_t p = 0; p < height.pixel_count(); ++p) {
    if (!mask[p]) continue;
    out.pixel(p)[0] =
        span > 0.0 ? static_cast<float>((height.pixel(p)[0] - range.low) / span) : 0.5f;
  }
  return out;
}

// The derived layers the stack does not hold yet, for stack.exr.
Image ExtraLayers(const Representation& r, const MaterialMaps& maps) {
  std::vector<const Image*> parts;
  for (const Image* image : {&maps.normals, &maps.albedo}) {
    if (r.maps().FindChannel(image->channel_names().front()) < 0) parts.push_back(image);
  }
  parts.push_back(&maps.height);
  std::vector<std::string> names;
  for (const Image* part : parts) {
    names.insert(names.end(), part->channel_names().begin(), part->channel_names().end());
  }
  Image extra(r.width(), r.height(), names);
  auto out = extra.values().begin();  // planar: the parts' planes one after another
  for (const Image* part : parts)
    out = std::copy(part->values().begin(), part->values().end(), out);
  return extra;
}

// The glTF F0 of a dielectric is min(0.04 specularColor, 1) specular (KHR_materials_specular,
// default IOR 1.5); Blender's Principled "Specular" and Substance's "specular level" s give
// F0 = 0.08 s.
constexpr double kGltfDielectricF0 = 0.04;
constexpr double kSpecularLevelF0 = 0.08;

struct PbrFiles {
  std::string metallic_roughness;
  std::string specular;
  double specular_color_factor = 1.0;
  nlohmann::json description;
};

// The microfacet maps beyond normal and base colour, for glTF, Blender and Substance.
PbrFiles WritePbrMaps(const Representation& r, const Mask& mask, const fs::path& folder,
                      const ImageWriteOptions& png16) {
  const Image& maps = r.maps();
  double largest_f0 = kGltfDielectricF0;
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    if (mask[p]) largest_f0 = std::max(largest_f0, double{maps.pixel(p)[MicrofacetShading::kF0]});
  }
  Image roughness(r.width(), r.height(), std::vector<std::string>{"roughness"});
  Image f0(r.width(), r.height(), std::vector<std::string>{"f0"});
  Image level(r.width(), r.height(), std::vector<std::string>{"Y"});
  Image metallic_roughness(r.width(), r.height(), std::vector<std::string>{"R", "G", "B"});
  Image specular(r.width(), r.height(), std::vector<std::string>{"R", "G", "B"});
  Image base(r.width(), r.height(), std::vector<std::string>{"R", "G", "B"});
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    if (!mask[p]) continue;
    const auto m = maps.pixel(p);
    roughness.pixel(p)[0] = m[MicrofacetShading::kRoughness];
    f0.pixel(p)[0] = m[MicrofacetShading::kF0];
    level.pixel(p)[0] = static_cast<float>(m[MicrofacetShading::kF0] / kSpecularLevelF0);
    // glTF: R unused (occlusion lives in its own texture), G roughness, B metallic (a dielectric).
    metallic_roughness.pixel(p)[0] = 1.0f;
    metallic_roughness.pixel(p)[1] = m[MicrofacetShading::kRoughness];
    for (int c = 0; c < 3; ++c) {
      specular.pixel(p)[c] = static_cast<float>(m[MicrofacetShading::kF0] / largest_f0);
    }
    for (int c = 0; c < 3; ++c) base.pixel(p)[c] = m[MicrofacetShading::kBase + c];
  }
  WriteImage(folder / "roughness.exr", roughness);
  WriteImage(folder / "roughness.png", roughness, png16);
  WriteImage(folder / "f0.exr", f0);
  WriteImage(folder / "specular_level.png", level, png16);
  WriteImage(folder / "metallic_roughness.png", metallic_roughness, png16);
  ImageWriteOptions srgb16 = png16;
  srgb16.encoding = ColourSpace::kSrgb;
  WriteImage(folder / "specular.png", specular, srgb16);
  WriteImage(folder / "base_color.exr", base);
  WriteImage(folder / "base_color.png", base, srgb16);
  PbrFiles files;
  files.metallic_roughness = "metallic_roughness.png";
  files.specular = "specular.png";
  files.specular_color_factor = largest_f0 / kGltfDielectricF0;
  files.description = {
      {"model", "diffuse + GGX, Smith height-correlated, Schlick; alpha = roughness^2"},
      {"base_color",
       {{"exr", "base_color.exr"},
        {"png", "base_color.png"},
        {"encoding", "linear float / 16-bit sRGB"}}},
      {"roughness",
       {{"exr", "roughness.exr"},
        {"png", "roughness.png"},
        {"encoding", "perceptual roughness, linear"}}},
      {"f0", {{"exr", "f0.exr"}, {"encoding", "grey Fresnel reflectance at normal incidence"}}},
      {"specular_level",
       {{"png", "specular_level.png"},
        {"encoding",
         "F0 / 0.08, 16-bit linear (Blender Principled Specular, "
         "Substance specular level)"}}},
      {"metallic_roughness",
       {{"png", "metallic_roughness.png"},
        {"encoding", "glTF: G roughness, B metallic (0), 16-bit linear"}}},
      {"specular",
       {{"png", "specular.png"},
        {"encoding",
         "KHR_materials_specular specularColorTexture, 16-bit sRGB: "
         "grey F0 / (0.04 specularColorFactor)"},
        {"specular_color_factor", files.specular_color_factor}}}};
  return files;
}

}  // namespace

nlohmann::json ExportMaps(const LoadedStack& stack, const fs::path& folder,
                          const ExportOptions& options, Progress* progress) {
  NullProgress no_progress;
  Progress& report = OrNull(progress, no_progress);
  const Representation& r = stack.representation;
  report.Start("export", (options.gltf ? 7 : 6) + (IsMicrofacet(r.shading()) ? 1 : 0));
  MaterialMapOptions map_options;
  map_options.height = options.height;
  map_options.values = StackValueEncoding(stack.provenance);
  map_options.sample_lights = stack.provenance.capture_lights;
  const MaterialMaps maps = ExtractMaterialMaps(r, map_options);
  report.Advance();

  ImageWriteOptions png16;
  png16.sample_type = SampleType::kUint16;
  WriteImage(folder / "normal.png", EncodeNormalMap(maps.normals, options.normal_convention),
             png16);
  report.Advance();

  ImageWriteOptions srgb8;
  srgb8.sample_type = SampleType::kUint8;
  srgb8.encoding = ColourSpace::kSrgb;
  WriteImage(folder / "albedo.png", maps.albedo, srgb8);
  report.Advance();

  const Range range = HeightRange(maps.height, maps.mask);
  WriteImage(folder / "height.exr", maps.height);
  ImageWriteOptions height16 = png16;
  height16.attributes["photomat:height_min"] = fmt::format("{:.9g}", range.low);
  height16.attributes["photomat:height_max"] = fmt::format("{:.9g}", range.high);
  WriteImage(folder / "height.png", NormalisedHeight(maps.height, maps.mask, range), height16);
  report.Advance();

  SaveRepresentation(folder / "stack.exr", r, stack.provenance, ExtraLayers(r, maps));
  report.Advance();

  nlohmann::json description = {
      {"format", "photomat-export"},
      {"version", 1},
      {"method", r.method()},
      {"source", stack.provenance.source},
      {"width", r.width()},
      {"height", r.height()},
      {"normals",
       {{"file", "normal.png"},
        {"convention", ToString(options.normal_convention)},
        {"encoding", "16-bit linear, (n + 1) / 2 per component"},
        {"source", maps.normals_source}}},
      {"albedo", {{"file", "albedo.png"}, {"encoding", "8-bit sRGB"}}},
      {"height",
       {{"file", "height.exr"},
        {"png", "height.png"},
        {"units", "pixels"},
        {"integrator", ToString(options.height)},
        {"min", range.low},
        {"max", range.high}}},
      {"stack", "stack.exr"},
  };
  PbrFiles pbr;
  if (IsMicrofacet(r.shading())) {
    pbr = WritePbrMaps(r, maps.mask, folder, png16);
    description["pbr"] = pbr.description;
    report.Advance();
  }
  if (options.gltf) {
    GltfTile tile;
    tile.aspect = static_cast<double>(r.height()) / r.width();
    tile.base_color_uri = "albedo.png";
    tile.normal_uri = "normal.png";
    if (options.normal_convention != NormalConvention::kOpenGl) {
      // glTF defines normal textures with +Y up.
      tile.normal_uri = "normal_gltf.png";
      WriteImage(folder / tile.normal_uri, EncodeNormalMap(maps.normals, NormalConvention::kOpenGl),
                 png16);
    }
    tile.height_uri = "height.png";
    tile.metallic_roughness_uri = pbr.metallic_roughness;
    tile.specular_uri = pbr.specular;
    tile.specular_color_factor = pbr.specular_color_factor;
    // Height in pixels, one pixel = tile.width / image width scene units.
    const double pixel = tile.width / r.width();
    tile.displacement_scale = (range.high - range.low) * pixel;
    tile.displacement_offset = range.low * pixel;
    WriteGltfTile(folder / "tile.gltf", tile);
    description["gltf"] = {{"file", "tile.gltf"},
                           {"width", tile.width},
                           {"displacement_scale", tile.displacement_scale},
                           {"displacement_offset", tile.displacement_offset}};
    report.Advance();
  }
  WriteJsonFile(folder / "export.json", description);
  report.Advance();
  report.Finish();
  return description;
}

}  // namespace photomat

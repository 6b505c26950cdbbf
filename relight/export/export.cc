#include "relight/export/export.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/export/gltf_tile.h"
#include "relight/formats/stack_file.h"

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

}  // namespace

nlohmann::json ExportMaps(const LoadedStack& stack, const fs::path& folder,
                          const ExportOptions& options, Progress* progress) {
  NullProgress no_progress;
  Progress& report = OrNull(progress, no_progress);
  const Representation& r = stack.representation;
  report.Start("export", options.gltf ? 7 : 6);
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

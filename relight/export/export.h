#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/progress.h"
#include "relight/export/material_maps.h"
#include "relight/export/normal_map.h"
#include "represent/stack/map_stack.h"

namespace photomat {

// `photomat export`: a representation's maps for graphics tools, written into one folder:
//   normal.png   16-bit tangent-space normal map (OpenGL +Y up, or DirectX)
//   albedo.png   8-bit sRGB albedo
//   height.exr   float height in pixel units ("height" channel)
//   height.png   16-bit height normalised to its range (range in export.json and the PNG's
//                "photomat:height_min/max" text)
//   tile.gltf    glTF 2.0 flat tile (+ tile.bin) with base colour, normal and displacement
//   stack.exr    the map stack with "height" (and the derived normal and albedo) layers added
//   export.json  what was written, the conventions and the height range
struct ExportOptions {
  NormalConvention normal_convention = NormalConvention::kOpenGl;
  HeightIntegrator height = HeightIntegrator::kPoisson;
  bool gltf = true;
};

// Writes the files above (each atomically) into `folder`, which must exist. Returns the
// description also written to export.json. Throws Error naming the file at fault.
nlohmann::json ExportMaps(const LoadedStack& stack, const std::filesystem::path& folder,
                          const ExportOptions& options = {}, Progress* progress = nullptr);

}  // namespace photomat

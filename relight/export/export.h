#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/progress.h"
#include "relight/export/material_maps.h"
#include "relight/export/normal_map.h"
#include "represent/stack/map_stack.h"
#include "represent/stack/stack_band_reader.h"
#include "represent/surface/tiled_poisson.h"

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

// Streamed export (README, "Streamed relighting and export"): the same files from a stack read
// band by band, for stacks too large to hold. Three passes over the stack: (1) normals and
// albedo per band (ExtractSurfaceMaps: every pixel's from its own maps, as in memory), written to
// normal.png and albedo.png and, with the gradients and the mask, to a scratch file beside the
// outputs; (2) the height by tiled Poisson (represent/surface/tiled_poisson.h) from the scratch
// file, to a second scratch file, with its mean and range over the mask, or with --height fc by
// Frankot-Chellappa, a whole-map FFT of the gradients read whole from the scratch file (about 50
// bytes per pixel beyond the bands: the field and its spectra); (3) height.exr, height.png and
// stack.exr (the stack's bands with the derived layers). Everything is written to temporary names
// and renamed at the end; the scratch files are removed however it ends. Normals and albedo equal
// the in-memory export's, and so does the fc height (the same gradients, the same transform); the
// Poisson height differs from the in-memory solve by the tiling (tiled_poisson_test.cc).
struct StreamedExportOptions {
  ExportOptions maps;
  TiledPoissonOptions poisson;
  // Bytes the bands may hold; 0: DefaultBandBudget(kMinimumExportMemory). The tiled Poisson's
  // window (16 bytes per pixel of tile + 2 overlap rows) comes on top.
  std::size_t memory_bytes = 0;
  // > 0: exactly this many rows per band (tests).
  int band_rows = 0;
  // One phase per pass.
  Progress* progress = nullptr;
};
inline constexpr std::size_t kMinimumExportMemory = std::size_t{16} << 20;

struct StreamedExportReport {
  int band_rows = 0;
  int passes = 0;
};

nlohmann::json ExportMapsStreamed(StackBandReader& stack, const std::filesystem::path& folder,
                                  const StreamedExportOptions& options = {},
                                  StreamedExportReport* report = nullptr);

// Bytes per pixel of a streamed export's band (the stack's band, relit images for the
// Lambertian fit, the surface maps, stack.exr's band).
std::size_t StreamedExportBytesPerPixel(const StackBandReader& stack);
// At most how many lights a stack is relit at to refit it (its capture's lights, or RefitLights'
// 193-light dome when it has none): the relit images' share of a band's memory.
std::size_t RelitLightsBound(const StackBandReader& stack);
// Bytes the in-memory ExportMaps holds for a stack of these dimensions (the stack, relit images,
// the maps and the Poisson solve): what decides between the two.
std::size_t InMemoryExportBytes(int width, int height, int maps, int channels);
// The bytes the export writes at most (and a streamed export's scratch files), for the disk check.
std::size_t ExportOutputBytes(int width, int height, int maps, int channels, bool gltf);

}  // namespace photomat

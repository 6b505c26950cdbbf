#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

#include "core/light_direction.h"
#include "core/progress.h"
#include "relight/render/relight.h"
#include "represent/stack/stack_band_reader.h"

namespace photomat {

// Streamed relighting (README, "Streamed relighting and export"): a map stack relit band by band
// of rows, each band read from the stack (StackBandReader), relit under every light and written
// straight into each light's image (ImageBandWriter: temporary names, renamed at the end), so
// memory follows the band, not the image. Every pixel's relit value depends on its own maps
// only, so the images equal the in-memory relighting (WriteRelitImage, WriteRelitSet) value for
// value, for any band height.

struct StreamedRelightOptions {
  RelitOutputOptions output;
  // Bytes the bands may hold (the stack's band, its maps, the relit bands being written); 0:
  // DefaultBandBudget(kMinimumRelightMemory) (core/memory_limits.h). Sets the band height
  // (RelightBandRows).
  std::size_t memory_bytes = 0;
  // > 0: exactly this many rows per band, whatever the budget (tests of band independence).
  int band_rows = 0;
  // One phase per pass over the stack, one step per band.
  Progress* progress = nullptr;
};
inline constexpr std::size_t kMinimumRelightMemory = std::size_t{16} << 20;

// IMPLEMENTER CHOICE: at most this many relit images are written at once, each an open file with
// its band in memory; more lights are relit in further passes over the stack (ceil(lights / 64)
// passes): the open files and the relit bands stay bounded whatever the number of lights, at the
// cost of reading the stack again (a sweep of up to 64 lights reads it once).
inline constexpr int kRelitImagesPerPass = 64;

struct StreamedRelightReport {
  int band_rows = 0;
  int passes = 0;  // passes over the stack
};

// The rows per band `memory_bytes` allows when relighting `lights` lights of a stack (at least 1,
// at most the stack's height): per row, the stack's stored channels and its gathered maps (4
// bytes each), and for each light relit at once its band and the writer's converted copy.
int RelightBandRows(std::size_t memory_bytes, const StackBandReader& stack, int lights);

// The bytes the relit images will take on disk at most (core/disk_space.h's ImageFileBytes per
// image, plus the manifest), for the check before writing.
std::size_t RelitOutputBytes(int width, int height, int channels, int lights, RelitFormat format);

// One image under `light` at `path`, streamed from `stack` (from its current row: a fresh
// reader). Throws Error naming the file at fault; nothing is then left at `path`.
StreamedRelightReport WriteRelitImageStreamed(const std::filesystem::path& path,
                                              StackBandReader& stack, const LightDirection& light,
                                              const StreamedRelightOptions& options = {});

// One image per light into `folder` (relit_000.png, ...) plus manifest.json, as WriteRelitSet.
// The images are renamed into place as each pass ends; on a fault the pass's images are not.
StreamedRelightReport WriteRelitSetStreamed(const std::filesystem::path& folder,
                                            StackBandReader& stack,
                                            const std::vector<LightDirection>& lights,
                                            const StreamedRelightOptions& options = {});

}  // namespace photomat

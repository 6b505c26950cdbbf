#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "core/colour.h"
#include "core/photometric_set.h"
#include "core/progress.h"
#include "core/sample_encoding.h"

namespace photomat {

// The on-disk layouts photomat reads a photometric set from.
enum class InputKind {
  kLpFile,    // images + a .lp light-position file
  kDiligent,  // filenames.txt, light_directions.txt, light_intensities.txt, mask.png
  kManifest,  // photomat's manifest.json (capture_manifest.h)
};
std::string_view ToString(InputKind kind);

struct InputLocation {
  InputKind kind;
  std::filesystem::path file;  // the light file or manifest; the DiLiGenT folder
};

// What is at `path`, decided from what is there (README, "Inputs"):
//   a .json file -> manifest; a .lp file -> lp; filenames.txt / light_directions.txt -> DiLiGenT
//   folder around it; a folder -> its manifest.json, else DiLiGenT files, else its only .lp file.
// Throws Error naming `path` when nothing matches or several .lp files make it ambiguous.
InputLocation DetectInput(const std::filesystem::path& path);

struct LoadOptions {
  // Divide each channel of each image by its light's intensity (DiLiGenT's light_intensities.txt,
  // manifest "intensity"). Off keeps the raw images and the intensities beside them.
  bool apply_intensities = true;
  // How integer images that say nothing about their encoding encode light (--colour-space);
  // before a manifest's "colour_space", after the files' own tags (ImageReadOptions). Default:
  // 8-bit sRGB, 16-bit linear.
  std::optional<ColourSpace> untagged_colour_space;
  // Ignores the files' tags: every integer image read as this (kLinear: the stored codes / max,
  // for response-curve calibration and tests of stored codes).
  std::optional<ColourSpace> colour_space;
  Progress* progress = nullptr;
};

// Peak bytes per pixel per image of a command that holds a whole loaded set (its images as float,
// their copy for fitting, the fit's maps): measured 36 (apps/batch/slurm.cc); 40 with a margin.
// What decides whether a command streams instead (`photomat export`) and what a batch task that
// holds a set asks Slurm for.
inline constexpr double kWholeSetBytesPerPixelImage = 40.0;

struct LoadedSet {
  PhotometricSet set;
  InputKind kind;
  // Per image, the number of clipped pixels (a channel at full scale): these are not measurements,
  // and robust fits leave them out.
  std::vector<std::size_t> saturated_pixels;
  // Ground-truth unit normals shipped with the set (synthetic manifests, DiLiGenT's
  // gt_normals.exr), if any.
  std::optional<std::filesystem::path> ground_truth_normals;
  // Per image, how its samples were decoded and why (for the stack's provenance).
  std::vector<ImageEncodingRecord> encodings;
};

// The light directions of any light file photomat reads (a .lp file, a manifest, DiLiGenT's
// light_directions.txt or its folder), without reading images. For relighting under a dome's
// lights or another capture's.
std::vector<LightDirection> ReadLightDirections(const std::filesystem::path& path);

// Reads images in parallel and warns (WarnIfEncodingsDisagree) when they were decoded
// differently. Every fault (missing or corrupt image, mixed sizes, malformed light
// data) is an Error naming the file and the fault.
LoadedSet LoadPhotometricSet(const std::filesystem::path& path, const LoadOptions& options = {});

}  // namespace photomat

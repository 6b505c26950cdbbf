#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "core/image.h"
#include "core/image_io.h"
#include "represent/stack/map_stack.h"

namespace photomat::app {

// What `synthesize` grows and `evaluate --synthesised` scores: a map stack (a photomat stack
// .exr, or a fit folder with `stack` naming one of its stacks) or a plain image (any format
// ReadImage reads: its channels are the maps).
struct MapsInput {
  std::filesystem::path path;        // the file read
  std::optional<LoadedStack> stack;  // set for map stacks
  Image image;                       // the maps (the stack's maps for stacks)
  ImageFileInfo info;                // how a plain image was encoded
};

// Throws Error naming the input when it is neither.
MapsInput LoadMapsInput(const std::filesystem::path& input,
                        const std::optional<std::string>& stack = std::nullopt);

// Writes maps to `path` as a plain image: 8-bit sRGB for .png/.jpg/.tif when the input was an
// 8-bit sRGB image (so unchanged pixels keep their codes), otherwise float (EXR) or 16-bit linear.
void WritePlainMaps(const std::filesystem::path& path, const Image& maps,
                    const ImageFileInfo& input_info);

// `photomat evaluate SAMPLE --synthesised OUT`: the quality measures of a synthesis (README,
// "Evaluation"), printed and, with `json`, written. `source_map` (optional) gives the seam score.
struct SynthesisEvaluationOptions {
  std::filesystem::path sample;
  std::filesystem::path synthesised;
  std::filesystem::path source_map;
  std::filesystem::path json;
  int patch_size = 7;
};
void EvaluateSynthesis(const SynthesisEvaluationOptions& options);

}  // namespace photomat::app

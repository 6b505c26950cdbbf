#pragma once

#include <CLI/CLI.hpp>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "capture/io/load_photometric_set.h"
#include "capture/synthetic/synthetic_capture.h"
#include "core/light_direction.h"
#include "represent/evaluation/evaluation.h"

namespace photomat::app {

// Helpers shared by the subcommands.

// "SLANT,TILT" in degrees.
LightDirection ParseSlantTilt(const std::string& text);
// "COUNT[,SLANT]": COUNT lights circling at SLANT degrees (default 60).
std::vector<LightDirection> ParseSweep(const std::string& text);
// "WxH".
std::pair<int, int> ParseSize(const std::string& text);
// "MIN,MAX" or one value (MIN = MAX) of the option `option`; throws Error naming it.
std::pair<double, double> ParseRange(std::string_view option, const std::string& text);

// Warns (stderr) about clipped pixels: `saturated` per image, `names` the images'.
void WarnAboutClippedPixels(const std::vector<std::size_t>& saturated,
                            const std::vector<std::string>& names);

// The photometric set a command reads: the positional INPUT, --ignore-intensities and
// --colour-space, the same in `fit`, `fit --method neural` and `evaluate --methods neural`.
struct SetInputOptions {
  std::filesystem::path input;
  bool raw_intensities = false;
  std::string colour_space;
  // The load options they ask for; Error for a colour space other than linear or srgb.
  LoadOptions ToLoadOptions() const;
};
void AddSetInputOptions(CLI::App& command, SetInputOptions& options);

// Loads a set with a progress bar and warns (stderr) about clipped pixels.
LoadedSet LoadSetForCommand(const std::filesystem::path& input, const LoadOptions& options);

// `--exr-compression NAME` on a command that writes map stacks: one of the lossless OpenEXR
// compressions, the default's name preset. The command's callback turns the name into the value
// with ParseExrCompression, whose error lists the allowed names. With `offer_auto`, "auto" is
// allowed too: the callback resolves it with FittedStackCompression.
void AddExrCompressionOption(CLI::App& command, std::string& name, bool offer_auto = false);

inline constexpr std::string_view kAutoExrCompression = "auto";

// The compression `name` asks for, "auto" resolved for a set with or without a mask.
// IMPLEMENTER CHOICE (README "Compression and threads"): "auto" is rle where a mask leaves a zero
// background, whose runs rle shrinks (DiLiGenT cat's PTM stack: 3.63 MB against 22.58), and none
// for full-frame maps, which rle does not shrink (cat's JPEGs without a mask: 22,586,266 bytes
// either way, OpenEXR keeping a chunk raw when rle does not pay) but spends about a tenth of a
// PTM fit's CPU trying.
ExrCompression FittedStackCompression(std::string_view name, bool masked);

// `--memory MB` on a streamed command: the bytes `bands` (what they hold, for the help) may use;
// 0 (not given) leaves the default to the step: DefaultBandBudget(minimum) (core/memory_limits.h).
void AddBandMemoryOption(CLI::App& command, std::size_t& memory_mb, std::string_view bands,
                         std::size_t minimum);

// Creates `folder` (and parents); Error naming it on failure.
void CreateFolder(const std::filesystem::path& folder);

// The evaluation table as printed by `evaluate` and `demo`.
std::string FormatEvaluationTable(const std::vector<MethodEvaluation>& evaluations);

// Options of a synthetic capture, shared by `generate` and `demo`.
struct GenerateOptions {
  SyntheticMaterialOptions material;
  SyntheticRenderOptions render;
  std::optional<std::filesystem::path> lights;  // default: the thesis grid
  bool exr = false;
};
// Renders and writes the capture; returns the number of images.
int WriteSyntheticSet(const std::filesystem::path& folder, const GenerateOptions& options);

}  // namespace photomat::app

#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>

#include "core/image.h"
#include "core/progress.h"
#include "represent/model/representation.h"
#include "synthesize/texture/block_placement.h"
#include "synthesize/texture/image_quilting.h"
#include "synthesize/texture/pixel_synthesis.h"
#include "synthesize/texture/source_map.h"

namespace photomat {

// Growing a representation (or any maps) to a new size: stage 2 of the thesis's framework. A
// synthesis is planned on a guide (the maps whose errors choose what goes where) into a source
// map, which is then applied to the maps to grow; by default the guide is the maps themselves.
// Only maps are touched: the light basis is the sample's and relights the result unchanged
// (thesis 6.2), so every representation, and plain images, synthesise alike.

enum class SynthesisMethod { kQuilt, kPixel };
std::string_view ToString(SynthesisMethod method);
// "quilt" or "pixel"; throws Error otherwise.
SynthesisMethod ParseSynthesisMethod(std::string_view name);

struct SynthesisOptions {
  SynthesisMethod method = SynthesisMethod::kQuilt;
  SynthesisTarget target;
  QuiltOptions quilt;
  PixelSynthesisOptions pixel;
};

struct SynthesisPlan {
  SourceMap source_map;
  std::optional<BlockPlacement> placement;  // quilting only
  // What was done (method, parameters, seed, sample size); recorded in grown stacks' details.
  nlohmann::json description;
};

// Plans target.width x target.height from `guide`. Throws Error for bad parameters.
SynthesisPlan PlanSynthesis(const Image& guide, const SynthesisOptions& options,
                            Progress* progress = nullptr);

// The representation's maps grown along `map` (same method, layout and light basis); the
// details gain "synthesis": `description`. Throws Error if the map was made for another sample
// size.
Representation ApplySourceMap(const Representation& representation, const SourceMap& map,
                              const nlohmann::json& description = {});

// Plans on `guide` (the representation's own maps when null) and grows the representation.
Representation Synthesize(const Representation& representation, const SynthesisOptions& options,
                          Progress* progress = nullptr, const Image* guide = nullptr);

}  // namespace photomat

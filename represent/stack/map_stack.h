#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/image_io.h"
#include "core/light_direction.h"
#include "core/sample_encoding.h"
#include "represent/model/representation.h"

namespace photomat {

// A representation on disk: one multi-layer OpenEXR (float32) whose channels are the maps, named
// by meaning ("normal.X", "albedo.R", "ptm.a3.G", "eigen.2.B", "image0.R"), so any EXR viewer shows
// each term as a layer. The header attribute "photomat:stack" holds JSON (README, "Map stacks"):
//   {"format": "photomat-map-stack", "version": 1, "method": "ptm",
//    "layout": {...MapLayout}, "channels": [map names in layout order],
//    "basis": {...LightBasis, everything needed to turn a light into coefficients},
//    "details": {...}, ["shading": {"kind": "microfacet"} for pbr, with layout.shading_maps],
//    "capture": {"lights": [[x, y, z], ...], "colour_space": "linear",
//    "source": "...", "images": [{"file": "img_000.png", "encoding": "srgb",
//    "decided_by": "png-srgb", "evidence": "PNG sRGB chunk"}, ...]}}
// ("images": how each input image was decoded to linear light, DecideSampleEncoding; omitted
// when unknown.)
inline constexpr const char* kStackAttribute = "photomat:stack";
inline constexpr const char* kStackFormat = "photomat-map-stack";

// Where the maps came from.
struct StackProvenance {
  // A constructor rather than aggregate initialisation, so that {lights, space, source} leaves
  // `images` empty without a missing-initializer warning.
  StackProvenance(std::vector<LightDirection> lights = {}, std::string space = "linear",
                  std::string from = {}, std::vector<ImageEncodingRecord> decoded = {})
      : capture_lights(std::move(lights)),
        colour_space(std::move(space)),
        source(std::move(from)),
        images(std::move(decoded)) {}

  std::vector<LightDirection> capture_lights;
  std::string colour_space;
  std::string source;
  // How each input image was decoded (LoadedSet::encodings); empty when unknown.
  std::vector<ImageEncodingRecord> images;
};

// Atomic write; throws Error naming `path`. Every `compression` is lossless: the maps read back
// bit for bit.
void SaveRepresentation(const std::filesystem::path& path, const Representation& representation,
                        const StackProvenance& provenance = {},
                        ExrCompression compression = kDefaultExrCompression);
// The same with extra layers beside the maps (named channels of the maps' size that relighting
// does not read, e.g. "height" and derived "normal.X/Y/Z" from `photomat export`), listed in the
// description as "extra_layers". Throws Error if a name repeats a map's.
void SaveRepresentation(const std::filesystem::path& path, const Representation& representation,
                        const StackProvenance& provenance, const Image& extra_layers,
                        ExrCompression compression = kDefaultExrCompression);

struct LoadedStack {
  Representation representation;
  StackProvenance provenance;
  Image extra_layers = {};  // empty when the stack has none
};
// Throws Error naming `path` when it is not a photomat map stack or its description is damaged.
LoadedStack LoadRepresentation(const std::filesystem::path& path);
// The part of LoadRepresentation after the EXR is read: the "photomat:stack" `description` (JSON
// text) applied to the file's channels. Throws Error naming `path` (fuzzed: tests/fuzz).
LoadedStack StackFromDescription(const std::string& description, const Image& stored,
                                 const std::filesystem::path& path);

// The folder `photomat fit --out DIR` writes: one stack per method and a "stacks.json":
//   {"format": "photomat-fit", "version": 1, "input": "...", "stacks": {"gradient":
//   "gradient.exr"}}
inline constexpr const char* kFitManifestName = "stacks.json";
void WriteFitManifest(const std::filesystem::path& folder, const std::string& input,
                      const std::map<std::string, std::string>& stacks);
// Stack files by method name, from a fit folder.
std::map<std::string, std::filesystem::path> ReadFitManifest(const std::filesystem::path& folder);

// `path` is a stack file (returned as is) or a fit folder, where `method` picks the stack (may be
// omitted when the folder holds one). Throws Error listing the methods available.
std::filesystem::path ResolveStack(const std::filesystem::path& path,
                                   const std::optional<std::string>& method);

}  // namespace photomat

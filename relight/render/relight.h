#pragma once

#include <filesystem>
#include <string_view>
#include <vector>

#include "core/colour.h"
#include "core/light_direction.h"
#include "core/progress.h"
#include "represent/model/representation.h"

namespace photomat {

// Rendering a representation under new lights and writing the results.

// `count` lights evenly spaced in tilt (starting at 0) at one slant: the light circling the sample.
std::vector<LightDirection> LightSweep(int count, double slant_degrees);

enum class RelitFormat {
  kPng8,   // 8-bit sRGB PNG, for looking at
  kPng16,  // 16-bit linear PNG, for measuring
  kExr,    // float OpenEXR
};
std::string_view ToString(RelitFormat format);
// "png8", "png16", "exr"; throws Error otherwise.
RelitFormat ParseRelitFormat(std::string_view name);
// The format a file name asks for: .exr -> kExr, .png/.tif -> kPng8 unless 16-bit is asked.
std::string_view Extension(RelitFormat format);

struct RelitOutputOptions {
  RelitFormat format = RelitFormat::kPng8;
  RelightOptions relight;
  // How the representation's relit values encode light: kSrgb for .ptm/.rti files (display codes
  // / 255), decoded to linear before writing, so png8 output shows exactly what PTM and RTI
  // viewers show.
  ColourSpace values = ColourSpace::kLinear;
};

// One image; throws Error naming `path`.
void WriteRelitImage(const std::filesystem::path& path, const Representation& representation,
                     const LightDirection& light, const RelitOutputOptions& options = {});

// One image per light into `folder` (relit_000.png, ...) plus a manifest.json listing the lights,
// so the folder is itself a photometric set that every photomat stage reads.
void WriteRelitSet(const std::filesystem::path& folder, const Representation& representation,
                   const std::vector<LightDirection>& lights,
                   const RelitOutputOptions& options = {}, Progress* progress = nullptr);

}  // namespace photomat

#pragma once

#include <filesystem>

#include "core/image.h"

namespace photomat {

// Writes `codes` (values in [0, 1] meant for the screen as they are: normal-map colours, grey
// heights, heat-map colours) as an 8-bit PNG whose codes are round(255 v), tagged sRGB. Tagged
// linear, browsers would gamma-correct it (a PNG gAMA of 1.0) and wash the colours out.
void WriteDisplayCodes(const std::filesystem::path& path, const Image& codes);

}  // namespace photomat

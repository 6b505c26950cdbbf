#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/light_direction.h"

namespace photomat {

// Reads light directions to compare a calibration with: any light file photomat reads
// (ReadLightDirections: .lp, manifest, DiLiGenT light_directions.txt or folder) or a plain vector
// list, "x y z" a line with an optional first line holding only the count (the University of
// Washington photometric-stereo sets' lights.txt). Throws Error naming the file and line.
std::vector<LightDirection> ReadLightList(const std::filesystem::path& path);

// Per-light intensities, one line per light holding one value (grey) or one per channel, as
// DiLiGenT's light_intensities.txt ("r g b"). Throws Error naming the file and line for a
// non-number, a non-positive value, or lines of different lengths.
std::vector<std::vector<float>> ReadLightIntensities(const std::filesystem::path& path);
// Writes them in the same form (9 significant digits), atomically.
void WriteLightIntensities(const std::filesystem::path& path,
                           const std::vector<std::vector<float>>& intensities);

}  // namespace photomat

#pragma once

#include <filesystem>
#include <vector>

#include "core/light_direction.h"

namespace photomat {

// Reads light directions to compare a calibration with: any light file photomat reads
// (ReadLightDirections: .lp, manifest, DiLiGenT light_directions.txt or folder) or a plain vector
// list, "x y z" a line with an optional first line holding only the count (the University of
// Washington photometric-stereo sets' lights.txt). Throws Error naming the file and line.
std::vector<LightDirection> ReadLightList(const std::filesystem::path& path);

}  // namespace photomat

#pragma once

#include <filesystem>
#include <vector>

#include "core/near_light.h"  // NearLight and its sample frame

namespace photomat {

// Reads near lights, one "x y z [intensity]" a line in the sample frame (pixel units); blank and
// '#' lines are skipped, an optional first line may hold only the count. Throws Error naming the
// file and line for malformed numbers, a light at or below the sample plane (z <= 0) or a
// non-positive intensity.
std::vector<NearLight> ReadNearLights(const std::filesystem::path& path);

}  // namespace photomat

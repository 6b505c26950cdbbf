#pragma once

#include <filesystem>
#include <optional>
#include <vector>

#include "core/light_direction.h"

namespace photomat {

// The files of a DiLiGenT object folder (Shi et al., CVPR 2016):
//   filenames.txt          one image name a line
//   light_directions.txt   "x y z" a line, row i for image i (x right, y up, z toward the camera)
//   light_intensities.txt  "r g b" a line (optional here; DiLiGenT always has it)
//   mask.png               object mask (optional)
//   gt_normals.exr         ground-truth normals (optional; photomat's test data adds it)
struct DiligentFiles {
  std::vector<std::filesystem::path> images;
  std::vector<LightDirection> lights;
  std::vector<std::vector<float>> intensities;  // empty when the file is absent
  std::optional<std::filesystem::path> mask;
  std::optional<std::filesystem::path> ground_truth_normals;
};

// Parses and cross-checks the text files (counts must agree; every line must hold 3 finite
// numbers; vectors must be non-zero and not below the sample plane; intensities positive).
// Throws Error naming the file and line at fault.
DiligentFiles ReadDiligentFiles(const std::filesystem::path& folder);

}  // namespace photomat

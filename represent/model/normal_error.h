#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>

#include "core/image.h"

namespace photomat {

// Angular error of estimated unit normals against ground truth (thesis-independent; DiLiGenT's
// measure), over the pixels in `mask` where the truth is non-zero.
struct NormalErrorStats {
  std::size_t pixels = 0;
  double mean_degrees = 0.0;
  double median_degrees = 0.0;
  double max_degrees = 0.0;
  double fraction_below_5_degrees = 0.0;
  double fraction_below_10_degrees = 0.0;
  nlohmann::json ToJson() const;
};

// Throws Error if the images differ in size or have fewer than 3 channels, or no pixel is valid.
NormalErrorStats CompareNormals(const Image& estimated, const Image& truth, const Mask& mask);

}  // namespace photomat

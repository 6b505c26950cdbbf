#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <vector>

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

// CompareNormals over bands of rows (a streamed evaluation): each band's angular errors are kept
// in raster order, so that Summary() equals CompareNormals of the whole images bit for bit. Memory:
// 8 bytes per compared pixel.
class NormalErrors {
 public:
  // The same rows of the estimate, the truth and the mask (a mask of another width: every pixel).
  // Throws Error as CompareNormals does for bands that differ in size or channels.
  void Add(const Image& estimated, const Image& truth, const Mask& mask);
  // Throws Error when no pixel had both a ground-truth and an estimated normal.
  NormalErrorStats Summary() const;

 private:
  std::vector<double> errors_;
};

}  // namespace photomat

#include "synthesize/texture/boundary_cut.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstddef>

#include "core/error.h"

namespace photomat {

std::vector<int> MinimumErrorPath(std::span<const double> errors, int length, int width) {
  if (length < 1 || width < 1 || errors.size() != static_cast<std::size_t>(length) * width) {
    throw Error(
        fmt::format("a {}x{} strip with {} errors has no cut", width, length, errors.size()));
  }
  std::vector<double> cost(errors.begin(), errors.end());
  for (int r = 1; r < length; ++r) {
    for (int c = 0; c < width; ++c) {
      const double* above = &cost[static_cast<std::size_t>(r - 1) * width];
      double best = above[c];
      if (c > 0) best = std::min(best, above[c - 1]);
      if (c + 1 < width) best = std::min(best, above[c + 1]);
      cost[static_cast<std::size_t>(r) * width + c] += best;
    }
  }
  std::vector<int> path(length);
  const double* last = &cost[static_cast<std::size_t>(length - 1) * width];
  path[length - 1] = static_cast<int>(std::min_element(last, last + width) - last);
  for (int r = length - 2; r >= 0; --r) {
    const double* row = &cost[static_cast<std::size_t>(r) * width];
    const int next = path[r + 1];
    int best = next;
    // Lowest column among the equal minima: check left, centre, right in that order.
    for (int c = std::max(0, next - 1); c <= std::min(width - 1, next + 1); ++c) {
      if (row[c] < row[best] || (row[c] == row[best] && c < best)) best = c;
    }
    path[r] = best;
  }
  return path;
}

namespace {

// The strip columns [first, first + width) over all rows (vertical) or rows [first, first +
// width) over all columns (horizontal), laid out as `length` rows of `width` errors.
std::vector<double> Strip(std::span<const double> errors, int block, int first, int width,
                          bool vertical) {
  std::vector<double> strip(static_cast<std::size_t>(block) * width);
  for (int along = 0; along < block; ++along) {
    for (int across = 0; across < width; ++across) {
      const int u = vertical ? first + across : along;
      const int v = vertical ? along : first + across;
      strip[static_cast<std::size_t>(along) * width + across] =
          errors[static_cast<std::size_t>(v) * block + u];
    }
  }
  return strip;
}

std::vector<int> Cut(std::span<const double> errors, int block, int first, int width,
                     bool vertical) {
  std::vector<int> path =
      MinimumErrorPath(Strip(errors, block, first, width, vertical), block, width);
  for (int& p : path) p += first;
  return path;
}

}  // namespace

BlockCuts CutBlock(const OverlapShape& shape, std::span<const double> pixel_errors) {
  const int b = shape.block;
  if (pixel_errors.size() != static_cast<std::size_t>(b) * b) {
    throw Error(fmt::format("{} pixel errors for a {}-pixel block", pixel_errors.size(), b));
  }
  BlockCuts cuts;
  if (shape.left > 0) cuts.left = Cut(pixel_errors, b, 0, shape.left, true);
  if (shape.right > 0) cuts.right = Cut(pixel_errors, b, b - shape.right, shape.right, true);
  if (shape.top > 0) cuts.top = Cut(pixel_errors, b, 0, shape.top, false);
  if (shape.bottom > 0) cuts.bottom = Cut(pixel_errors, b, b - shape.bottom, shape.bottom, false);
  return cuts;
}

}  // namespace photomat

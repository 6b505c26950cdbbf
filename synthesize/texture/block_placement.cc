#include "synthesize/texture/block_placement.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace photomat {

int OverlapShape::PixelCount() const {
  const int inner_width = std::max(0, block - left - right);
  const int inner_height = std::max(0, block - top - bottom);
  return block * block - inner_width * inner_height;
}

bool PlacedBlock::TakesNew(int u, int v) const {
  if (!cuts.left.empty() && u < cuts.left[v]) return false;
  if (!cuts.right.empty() && u > cuts.right[v]) return false;
  if (!cuts.top.empty() && v < cuts.top[u]) return false;
  if (!cuts.bottom.empty() && v > cuts.bottom[u]) return false;
  return true;
}

std::vector<int> BlockPositions(int extent, int block, int overlap, bool tileable) {
  if (extent < 1 || block < 2 || overlap < 1 || 2 * overlap > block) {
    throw Error(fmt::format("no block grid for an extent of {} with block {} and overlap {}",
                            extent, block, overlap));
  }
  const int step = block - overlap;
  std::vector<int> positions;
  if (!tileable) {
    if (extent <= block) return {0};
    const int count = (extent - block + step - 1) / step + 1;
    for (int i = 0; i < count; ++i) positions.push_back(std::min(i * step, extent - block));
    return positions;
  }
  // Steps of extent / count must stay within [block / 2, block - 1]: every overlap at least one
  // pixel, and the last block's left and right (wrapping) strips must not meet.
  const int fewest = std::max(2, (extent + block - 2) / (block - 1));
  const int most = extent / ((block + 1) / 2);
  if (fewest > most) {
    throw Error(
        fmt::format("a tileable output of {} pixels cannot be quilted from {}-pixel blocks "
                    "(use a smaller block or a larger output)",
                    extent, block));
  }
  const int count =
      std::clamp(static_cast<int>(std::lround(static_cast<double>(extent) / step)), fewest, most);
  for (int i = 0; i < count; ++i) {
    positions.push_back(static_cast<int>(static_cast<long long>(i) * extent / count));
  }
  return positions;
}

void BlockPlacement::Paste(const PlacedBlock& block, SourceMap& canvas) const {
  for (int v = 0; v < block_size; ++v) {
    const int y = (block.y + v) % canvas_height;
    for (int u = 0; u < block_size; ++u) {
      if (!block.TakesNew(u, v)) continue;
      const int x = (block.x + u) % canvas_width;
      canvas.Set(x, y, {block.source.x + u, block.source.y + v});
    }
  }
}

SourceMap BlockPlacement::RenderSourceMap() const {
  SourceMap canvas(canvas_width, canvas_height, sample_width, sample_height);
  for (const PlacedBlock& block : blocks) Paste(block, canvas);
  if (canvas_width == width && canvas_height == height) return canvas;
  return canvas.Cropped(width, height);
}

}  // namespace photomat

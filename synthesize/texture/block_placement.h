#pragma once

#include <cstdint>
#include <vector>

#include "synthesize/texture/source_map.h"

namespace photomat {

// What every synthesis is asked for.
struct SynthesisTarget {
  int width = 0;
  int height = 0;
  // The output wraps: its right edge continues into its left edge and its bottom into its top,
  // so it tiles seamlessly.
  bool tileable = false;
  std::uint64_t seed = 1;
};

// Which pixels of a B x B block were already synthesised when it is placed: strips along its
// sides (left and top from the blocks before it in raster order; right and bottom only when a
// tileable output wraps onto its first column or row). Widths are 0 where there is no overlap.
struct OverlapShape {
  int block = 0;
  int left = 0;
  int top = 0;
  int right = 0;
  int bottom = 0;

  bool Contains(int u, int v) const {
    return u < left || v < top || u >= block - right || v >= block - bottom;
  }
  bool empty() const { return left == 0 && top == 0 && right == 0 && bottom == 0; }
  int PixelCount() const;
  friend bool operator==(const OverlapShape&, const OverlapShape&) = default;
};

// Minimum-error boundary cuts through the overlap strips of a block, one path per strip, shared
// by all channels. A path gives, for each row (vertical strips) or column (horizontal strips), the
// strip pixel it passes through, in block coordinates; the new block takes the path and its own
// side (left strip: u >= left[v]; right strip: u <= right[v]; top strip: v >= top[u]; bottom
// strip: v <= bottom[u]). Empty where the block has no such strip.
struct BlockCuts {
  std::vector<int> left, top, right, bottom;
  friend bool operator==(const BlockCuts&, const BlockCuts&) = default;
};

// One block of a quilt.
struct PlacedBlock {
  int column = 0;  // grid position
  int row = 0;
  int x = 0;  // output (canvas) position of its top-left pixel
  int y = 0;
  SamplePixel source;  // sample position of its top-left pixel
  OverlapShape overlap;
  BlockCuts cuts;
  // How the block was chosen: the random first block, a search, or the coherence shortcut.
  enum class Choice { kRandom, kSearch, kCoherence } choice = Choice::kRandom;

  // The cut mask: whether block pixel (u, v) takes this block's value (else it keeps what was
  // there).
  bool TakesNew(int u, int v) const;
  friend bool operator==(const PlacedBlock&, const PlacedBlock&) = default;
};

// Positions of blocks of size `block` along an output axis of length `extent`.
// Not tileable: every block_size - overlap pixels, the last block moved back to end at the
// extent (its overlap grows); an extent below the block gives one block (the canvas is then the
// block and the output its crop). Tileable: extent / count apart (rounded down), count chosen
// near extent / (block - overlap) and such that each overlap, including the one that wraps
// from the last block onto the first, is between 1 and block / 2. Throws Error when no count
// fits (an extent too small for a tileable output with this block).
std::vector<int> BlockPositions(int extent, int block, int overlap, bool tileable);

// A complete quilt: the block grid, where each block came from and how it was cut. Rendering it
// gives the source map; keeping it explicit lets a placement be inspected, tested and re-applied
// to any maps of the same sample.
struct BlockPlacement {
  int block_size = 0;
  int overlap = 0;
  int width = 0;  // the output
  int height = 0;
  int canvas_width = 0;  // >= output when not tileable (the output is its top-left crop)
  int canvas_height = 0;
  bool tileable = false;
  int sample_width = 0;
  int sample_height = 0;
  std::vector<int> column_positions;
  std::vector<int> row_positions;
  std::vector<PlacedBlock> blocks;  // raster order of the grid

  // Pastes one block onto a canvas source map (canvas_width x canvas_height, wrapping when
  // tileable) along its cuts.
  void Paste(const PlacedBlock& block, SourceMap& canvas) const;
  // Every block pasted in order, cropped to the output.
  SourceMap RenderSourceMap() const;
  friend bool operator==(const BlockPlacement&, const BlockPlacement&) = default;
};

}  // namespace photomat

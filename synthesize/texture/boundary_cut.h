#pragma once

#include <span>
#include <vector>

#include "synthesize/texture/block_placement.h"

namespace photomat {

// Efros-Freeman's minimum-error boundary cut (thesis fig. 5.3.5; spec 4.3 RECONSTRUCTED) by
// dynamic programming: through a strip of `length` rows and `width` columns of per-pixel errors
// (row-major), the 8-connected top-to-bottom path of least summed error, one column per row.
// E(0, c) = e(0, c); E(r, c) = e(r, c) + min(E(r-1, c-1), E(r-1, c), E(r-1, c+1)); backtracked
// from the smallest E in the last row. Ties go to the lowest column, so the path is
// deterministic. Throws Error for an empty strip or a size mismatch.
std::vector<int> MinimumErrorPath(std::span<const double> errors, int length, int width);

// The cuts of every overlap strip of a block, from the per-pixel overlap errors of the whole
// block (block x block, row-major; only overlap pixels are read). Vertical strips (left, right)
// are cut top to bottom, horizontal ones (top, bottom) left to right, each over the full block
// length; in a corner a pixel takes the new block only on the new side of both cuts.
BlockCuts CutBlock(const OverlapShape& shape, std::span<const double> pixel_errors);

}  // namespace photomat

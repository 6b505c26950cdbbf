#pragma once

#include "core/image.h"
#include "core/progress.h"
#include "synthesize/texture/block_placement.h"
#include "synthesize/texture/matching_space.h"
#include "synthesize/texture/overlap_search.h"
#include "synthesize/texture/source_map.h"

namespace photomat {

// Pixel-based multiresolution synthesis: the thesis's modified Wei-Levoy (section 5.3.1, spec
// 4.2), the comparison method. Coarse to fine over Gaussian pyramids of the sample and the
// output, each output pixel copies the sample pixel whose neighbourhood (the causal L-shaped half
// of a square at its level, plus the full square around its parent one level up) best matches,
// by exhaustive search; or, when it continues the previous pixel's source along the row (the
// "next column neighbour pixel"), without a search, except for a random share of forced searches.
struct PixelSynthesisOptions {
  // Pyramid levels above the finest; -1 picks the most (up to 4) that keep the coarsest sample
  // level at least 16 pixels and 3 neighbourhoods wide (IMPLEMENTER CHOICE: the thesis gives no
  // number).
  int levels = -1;
  // Odd side of the square whose causal half is matched at the current level (the thesis gives
  // no size; 5 is Wei-Levoy's smallest useful one).
  int neighbourhood = 5;
  // Odd side of the full square matched around the parent pixel.
  int parent_neighbourhood = 3;
  // Share a of pixels searched even when the next-column continuation is possible (thesis: 40-70 %
  // works for most textures; 1 reproduces Wei-Levoy).
  double forced_search_rate = 0.5;
  // The thesis matches by SAD.
  MatchingOptions matching = {ErrorMetric::kSad, ChannelScaling::kMinMax, {}};
  // kFast abandons candidate rows whose partial sums already exceed the best error found (exact:
  // the same pixels as kBruteForce, which sums every candidate in full).
  SearchMode search = SearchMode::kFast;
};

// Plans the output from `guide`: the returned map's pixels are finest-level sample pixels.
// Neighbours outside a non-tileable output are left out of the match. A tileable output reads
// its neighbourhoods toroidally (Wei-Levoy) and, past its last rows and columns, also matches the
// already synthesised first ones (IMPLEMENTER CHOICE: the causal half alone never sees the rows
// below, so the vertical wrap would only be matched through the parent levels). Ties go to the
// first candidate in raster order.
// Deterministic for a seed, whatever the thread count. Throws Error for parameters out of range
// or a sample too small for the neighbourhoods and levels.
SourceMap PlanPixelSynthesis(const Image& guide, const SynthesisTarget& target,
                             const PixelSynthesisOptions& options, Progress* progress = nullptr);

}  // namespace photomat

#pragma once

#include "core/image.h"
#include "core/progress.h"
#include "synthesize/texture/block_placement.h"
#include "synthesize/texture/matching_space.h"
#include "synthesize/texture/overlap_search.h"

namespace photomat {

// Image quilting in R^n: the thesis's modified Efros-Freeman (chapters 5.3 and 6.2).
struct QuiltOptions {
  // Block size B; 0 picks DefaultBlockSize(sample).
  int block_size = 0;
  // Overlap w_o; 0 picks DefaultOverlap(B) = round(B / 4), inside the thesis's B/6..B/3.
  int overlap = 0;
  // A candidate qualifies when its error is at most (1 + tolerance) times the best (Efros-Freeman
  // and the thesis: 0.1; the thesis found 0..0.1 alike).
  double tolerance = 0.1;
  // The best error is taken as at least error_floor times the error a block would have if every
  // overlap pixel differed from it as much as neighbouring sample pixels differ on average
  // (IMPLEMENTER CHOICE, spec 4.3: "when min_error = 0, fall back to an absolute epsilon").
  // Without it the exact continuation of the previous block (error 0, always a candidate at
  // stride 1) would be the only one that qualifies, and every search would copy the sample
  // verbatim; with it, candidates whose seams are no rougher than the texture itself compete.
  double error_floor = 1.0;
  // Candidates every `candidate_stride` pixels: 1 = every offset (Efros-Freeman), B = the grid of
  // non-overlapping blocks the thesis's counts suggest.
  int candidate_stride = 1;
  // The thesis's neighbour-block reuse (modification 1): when the sources of the blocks left,
  // above and above-left of the next block are adjacent in the sample, continue them without a
  // search, except for a random forced_search_rate share of the blocks (IMPLEMENTER CHOICE, spec
  // 4.3: the thesis's table 5.3.2 has no such rate; 0.5 is in its 40-70 % range for pixels).
  bool coherence = true;
  double forced_search_rate = 0.5;
  SearchMode search = SearchMode::kFast;
  MatchingOptions matching;
};

// The seam-quality preset for a sample of this size (`photomat synthesize --quality`;
// IMPLEMENTER CHOICE, measured in bench/synthesis_table): it trades some variety for fewer,
// closer seams (and, with fewer blocks, runs faster). Blocks a third of the sample's smaller side
// (clamped to [8, 64]) instead of a quarter: the seams per output area fall by about a quarter, and
// 2/3 of the sample's offsets per axis remain candidates. Tolerance 0 (the thesis found 0..0.1
// alike) and error floor 0.5 (blocks compete when their overlap differs half as much as
// neighbouring sample pixels, not as much): the best-matching blocks are taken. The SSD metric is
// kept, so the search stays FFT-fast. The same for every input; the quilt's nearest-patch
// distance comes from its seams.
QuiltOptions SeamQualityQuiltOptions(int sample_width, int sample_height);

// min(sample) / 4, clamped to [8, 64] and to the sample (IMPLEMENTER CHOICE: a quarter of the
// sample keeps its structures whole while leaving 3/4 of the sample's offsets as candidates).
int DefaultBlockSize(int sample_width, int sample_height);
int DefaultOverlap(int block_size);

// Plans a quilt of target.width x target.height from `guide` (the maps whose errors choose the
// blocks; any number of channels). Deterministic for a seed, whatever the thread count. Throws
// Error for parameters out of range (block larger than the sample, overlap outside 1..B/2,
// negative tolerance, a rate outside [0, 1], ...).
BlockPlacement PlanQuilt(const Image& guide, const SynthesisTarget& target,
                         const QuiltOptions& options, Progress* progress = nullptr);

}  // namespace photomat

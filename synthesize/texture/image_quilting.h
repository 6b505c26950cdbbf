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
  // and the thesis: 0.1; the thesis found 0..0.1 alike). IMPLEMENTER CHOICE (issue 18, measured in
  // bench/synthesis_table and bench/peer_table): 0, the best-matching blocks, with the error
  // floor below providing the choice among them.
  double tolerance = 0.0;
  // The best error is taken as at least error_floor times the error a block would have if every
  // overlap pixel differed from it as much as neighbouring sample pixels differ on average
  // (IMPLEMENTER CHOICE, spec 4.3: "when min_error = 0, fall back to an absolute epsilon").
  // Without it the exact continuation of the previous block (error 0, always a candidate at
  // stride 1) would be the only one that qualifies, and every search would copy the sample
  // verbatim; with it, candidates whose seams are at most about as rough as the texture itself
  // compete. 0.5 (issue 18): a block competes when its overlap differs half as much as
  // neighbouring sample pixels (1.0, the variety preset's, lets rougher seams through).
  double error_floor = 0.5;
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

// The variety preset (`photomat synthesize --variety`; the defaults before issue 18): more
// different pieces of the sample at the cost of more and rougher seams. Blocks a quarter of the
// sample's smaller side (clamped to [8, 64]) instead of a third (about a third more seams per
// output area, 3/4 of the sample's offsets per axis candidates), tolerance 0.1 (Efros-Freeman's)
// and error floor 1.0 (blocks compete when their overlap differs as much as neighbouring sample
// pixels). The defaults are chosen for the nearest-patch distance at G'MIC's level or below
// (README "Synthesis"); this preset's distance is higher, by 1.1 to 2 x on the exemplars.
QuiltOptions VarietyQuiltOptions(int sample_width, int sample_height);

// min(sample) / 3, clamped to [8, 64] and to the sample (IMPLEMENTER CHOICE, issue 18: a third
// keeps the sample's structures whole and makes about a quarter fewer seams per output area than
// a quarter, while 2/3 of the sample's offsets per axis remain candidates).
int DefaultBlockSize(int sample_width, int sample_height);
int DefaultOverlap(int block_size);

// Plans a quilt of target.width x target.height from `guide` (the maps whose errors choose the
// blocks; any number of channels). Deterministic for a seed, whatever the thread count. Throws
// Error for parameters out of range (block larger than the sample, overlap outside 1..B/2,
// negative tolerance, a rate outside [0, 1], ...).
BlockPlacement PlanQuilt(const Image& guide, const SynthesisTarget& target,
                         const QuiltOptions& options, Progress* progress = nullptr);

}  // namespace photomat

#pragma once

#include <functional>

#include "core/image.h"
#include "represent/surface/surface_integration.h"

namespace photomat {

// Poisson (least-squares) integration of a gradient field too large to solve at once (README,
// "Streamed relighting and export"): height from the normals of a 50-megapixel map in bounded
// memory, the gradients read band by band in row order, twice.
//
//   1. Coarse pass: the gradients averaged over blocks of `coarse_factor` x `coarse_factor`
//      pixels (and scaled to slopes per block) are integrated (PoissonIntegrator, factorised)
//      over the blocks that hold a masked pixel: the surface's shape at large scale.
//   2. Tile pass: the image is cut into tiles of `tile` x `tile` pixels, each solved by
//      IntegratePoisson over itself and `overlap` pixels around it (the tiles of one row of tiles
//      in parallel; tiles wholly inside the mask share one factorised PoissonIntegrator per size).
//      Each solve is known up to a constant per connected piece of the mask inside it; that
//      constant is the mean difference to the coarse height, interpolated bilinearly, over the
//      piece. Neighbouring tiles are blended with linear weights across the 2 x overlap pixels they
//      share (weights sum to 1), so no seam is left where their solutions differ.
//
// Memory: one row of tiles with its overlaps (gradients, mask and the blended height: 16 bytes per
// pixel of (tile + 2 overlap) rows), the factorised tiles (about 40 MB each for 320 x 320: the
// row's full tiles' at most 3 sizes and one per thread for a tile the mask cuts) plus the coarse
// grid (at most about 2^20 blocks, IMPLEMENTER CHOICE: coarse_factor grows from the given one until
// the grid is that small), whose solve is factorised whatever its size: at 2^20 blocks about
// 0.5 GB and 15 s, against a minute of conjugate gradients (measured; a grid capped at 2^18
// blocks instead, 16 x 16 at 48 MP, would be cheaper but was 2.7 times less accurate on a
// 1024 x 1024 bricks map: relative RMS 3.1e-3 against 1.2e-3 with 8 x 8 blocks). The
// result is zero-mean over the mask up to the coarse grid's approximation and 0 outside the mask;
// its accuracy against the in-memory IntegratePoisson is measured in tiled_poisson_test.cc.
struct TiledPoissonOptions {
  // IMPLEMENTER CHOICE: 256-pixel tiles with 32 pixels of overlap on each side (a 320 x 320
  // solve of about 0.1 M unknowns per tile), stitched by a coarse grid of 8 x 8-pixel blocks.
  int tile = 256;
  int overlap = 32;
  int coarse_factor = 8;
};

// The gradients, read in row order: `next(rows)` returns the next `rows` rows (fewer at the end)
// as an image of 3 channels: p and q (GradientsFromNormals' slopes) and the mask (1 inside, 0
// outside). `rewind()` goes back to row 0 for the second pass.
struct GradientRows {
  std::function<Image(int rows)> next;
  std::function<void()> rewind;
};

// The coarse grid's block side for a width x height image: options.coarse_factor, doubled until
// the grid has at most kMaxCoarseBlocks blocks.
int CoarseFactor(int width, int height, const TiledPoissonOptions& options);
inline constexpr long kMaxCoarseBlocks = long{1} << 20;

// Integrates the width x height field read from `gradients` and hands the height to `write` in
// row order, in bands of 2 channels: the height (pixel units) and the mask (1 inside, 0 outside).
// Throws Error when the mask selects no pixel or a solve fails.
void IntegrateTiledPoisson(int width, int height, const GradientRows& gradients,
                           const std::function<void(ConstImageView height_rows)>& write,
                           const TiledPoissonOptions& options = {});

// The same on an image held in memory (2 channels p, q; `mask` empty: every pixel): for tests
// and for comparing with IntegratePoisson.
Image IntegrateTiledPoisson(const Image& gradients, const Mask& mask,
                            const TiledPoissonOptions& options = {});

// The Poisson height of an image held in memory, as the in-memory exports make it: the exact
// solve (IntegratePoisson, factorised) up to kDirectPoissonUnknowns masked pixels, the tiled one
// above (IMPLEMENTER CHOICE: the whole field's conjugate gradients took 72 s for a 1024 x 1024
// map and grow as the pixels to the power 1.5, against 4 s for the tiled solve, which differed
// from it by 1.5e-4 of the height range RMS there; so a map gets the same height in memory as
// streamed).
Image IntegratePoissonAnySize(const Image& gradients, const Mask& mask);

}  // namespace photomat

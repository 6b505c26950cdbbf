#pragma once

#include <cstdint>
#include <vector>

#include "core/progress.h"
#include "synthesize/solid/frame_field.h"
#include "synthesize/solid/similarity_set.h"
#include "synthesize/volume/volume.h"

namespace photomat {

// Exemplar-based solid synthesis with vector-field control (Su 2008; ../shared/specs/
// solid-texture-vector-field.md), a 3D version of Lefebvre and Hoppe's parallel controllable
// synthesis: a pyramid of exemplar coordinates, each level upsampled from the last, jittered by a
// hash of the voxel, then corrected by matching appearance-space neighbourhoods (8 diagonal
// neighbours, each the mean of 4 predictions) among 24 k-coherence candidates and the current
// coordinate. With a frame field, upsampling and neighbourhoods follow the local frame
// (anisometric synthesis). The output takes every channel of the exemplar voxel its coordinate
// points to, so any representation's maps grow as a solid.
//
// Determinism: jitter comes from a hash of (seed, level, voxel); correction updates the 8 parity
// classes of voxels one after another (Gauss-Seidel), and voxels of one class never read each
// other, so the result is the same bytes for any thread count.
struct ExemplarSolidOptions {
  ImageExtent size = ImageExtent::Cube(128);
  double jitter = 0.7;  // r: jitter of h_l * r per level
  // Correction passes per level (Lefebvre and Hoppe's 2; the thesis gives none). 0 turns
  // correction off (upsampling and jitter only).
  int correction_passes = 2;
  std::uint64_t seed = 1;
  // Histogram matching after Kopf et al. 2007 (section 4.2): the first step of the bins'
  // log-prices below; 0 turns it off (the thesis has none). IMPLEMENTER CHOICE, on by default:
  // on the finest level each candidate pays a price for the bins (64 per exemplar channel, over
  // the exemplar's range) its value falls in: its distance (weighted by occupancy matching), plus
  // a floor of 2 % of the exemplar neighbourhoods' mean squared norm (so that a perfect match
  // pays too), is multiplied by e^(mean over channels of its bins' log-prices), each bounded by
  // +-1. Per subpass, 16 rounds: every voxel of the class picks its cheapest candidate at the
  // current prices, and the log-price of each bin the level's resulting histogram over-fills
  // rises, of each it under-fills falls, by a step that starts at this value, grows by 1.5 while
  // the sign holds and halves when it flips (Rprop); the round whose picks bring the level's
  // histogram closest to the exemplar's is kept (plain matching included) and the prices carry
  // over to the next subpass. The finest level only: it decides the output's colours, and a
  // coarse level's coordinates are a lattice subsample whose histogram differs from the
  // exemplar's even for a perfect copy. Without it the result over-uses some colours (wood 16^3
  // grown to 64^3: histogram L1 0.072, against 0.011 for the scrambled jitter-only result; with
  // it 0.002); the cost is a neighbourhood-match error 0 to 40 % higher (README, solid textures).
  double histogram_matching = 0.05;
  // Occupancy matching, lambda of the weight below; 0 turns it off (the thesis has none).
  // IMPLEMENTER CHOICE, on by default: at the start of every subpass the level's coordinates are
  // counted per block of the exemplar (B^3 blocks, B = min(exemplar side, level side / 2), so at
  // least 8 voxels are expected in each); a candidate in a block the result uses more than a
  // uniform copy would has its neighbourhood distance multiplied by
  // 1 + lambda max(0, count / expected - 1). Without it k-coherence candidates keep leading to a
  // few exemplar regions (on 16^3 wood grown to 64^3, 10 % of the exemplar voxels filled 59 % of
  // the result) and the colour histogram drifts (README, solid textures).
  double occupancy_matching = 1.0;
  // Anisometric synthesis when set: the frames over the output (any size; resampled to it).
  const FrameField* field = nullptr;
};

struct PassReport {
  int level = 0;
  int spacing = 0;  // h_l
  int pass = 0;
  // Mean over the level's voxels of |N_S(p) - N_E(S[p])|^2 after the pass (the internal
  // objective; it cannot rise within a pass, since the current coordinate is a candidate).
  double objective = 0;
};

struct ExemplarSolidResult {
  Image volume;       // the exemplar's channels
  Image coordinates;  // "exemplar.x/y/z": the exemplar voxel of each output voxel
  std::vector<PassReport> passes;
};

// `prepared` must come from `exemplar` (PrepareExemplar); its Gaussian-stack levels, when it has
// them, are matched at the levels of their spacing. Throws Error for sizes below 1 or a negative
// jitter or histogram weight.
ExemplarSolidResult SynthesizeExemplarSolid(const Image& exemplar, const PreparedExemplar& prepared,
                                            const ExemplarSolidOptions& options,
                                            Progress* progress = nullptr);

// The baseline of uniformly random exemplar coordinates (a hash of seed and voxel).
ExemplarSolidResult RandomCoordinateSolid(const Image& exemplar, const ExemplarDomain& domain,
                                          ImageExtent size, std::uint64_t seed);

}  // namespace photomat

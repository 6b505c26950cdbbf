#pragma once

#include <filesystem>

#include "synthesize/surface/reaction_diffusion.h"

namespace photomat {

// A Gray-Scott pattern file of Ready (GollyGang/ready, VTK XML ImageData with an <RD> block), as
// shipped with Pearson's (1993) reference settings: the rule's parameters, its grid and the
// initial square. The ImageData arrays are not read: Ready's files store them as zeros and build
// the initial state on load from the <initial_pattern_generator>.
struct ReadyGrayScottPattern {
  GrayScottParameters parameters;  // D_a, D_b, F, K and the seed square's side (fraction)
  double time_step = 1.0;
  double dx = 1.0;  // grid spacing
  int width = 0;    // grid nodes (the ImageData's whole extent)
  int height = 0;
  bool wrap = false;  // periodic boundaries
};

// Throws Error naming `path` when it is not a Ready file, the rule is not Gray-Scott, or a
// parameter is missing or not a number.
ReadyGrayScottPattern ReadReadyGrayScott(const std::filesystem::path& path);

}  // namespace photomat

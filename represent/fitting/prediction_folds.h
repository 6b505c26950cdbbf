#pragma once

#include <filesystem>
#include <span>
#include <vector>

#include "represent/model/method.h"

namespace photomat {

// A fold of the ability-of-prediction (thesis 4.5): a fit from the images `fitted`, which
// predicts each image of `predicted` (none of them fitted).
struct PredictionFold {
  std::vector<int> fitted;
  std::vector<int> predicted;
};

// The folds of a set of `images` images. `hold_out_every` 0: leave-one-out, fold k predicting image
// k from all the others (`images` folds). K > 0: one fold holding out the images i % K == 0 (every
// K-th light from the first) and fitted from the rest. The one place both the in-memory and the
// streamed evaluations (and the neural one) take their folds from.
std::vector<PredictionFold> PredictionFolds(int images, int hold_out_every);

// Throws Error naming `source` when a fold fits fewer images than `method` needs, before any fit
// ("a prediction fold fits N images; M needs K"): the in-memory and streamed evaluations' check.
void CheckFoldsFit(std::span<const PredictionFold> folds, const Method& method,
                   const std::filesystem::path& source);

}  // namespace photomat

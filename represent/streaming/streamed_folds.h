#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <span>

#include "capture/io/streamed_set.h"
#include "core/progress.h"
#include "represent/fitting/observations.h"
#include "represent/fitting/prediction_folds.h"
#include "represent/fitting/robust_fit.h"
#include "represent/model/method.h"
#include "represent/model/representation.h"

namespace photomat {

// Streamed prediction folds (README, "Streamed relighting and export"): the fits of the
// ability-of-prediction (leave-one-out, held-out lights) made band by band, so that evaluating
// how a method predicts unseen lights needs memory for a band, not for the set. Every method is
// per pixel once its light basis is known, and the bases of Eigen-k, rbf and bilinear follow from
// the Gram matrix of every image (RowGram, one streamed pass first): a fold's basis takes the
// rows and columns of its fitted images, as the in-memory fit of that fold does. So a band's fold
// fit is the rows of the in-memory fold fit, to float rounding. Robust folds too: each fold's
// robust fit of the band, its measured masks found on the band as captured, made once per band
// and fold for all methods (3I, Gradient, PTM, PTM-LRGB, HSH and pbr, whose nonlinear fit starts
// from it, are per pixel from its weights). Robust Eigen-k, rbf and bilinear fit on the fold's
// imputed profiles, whose Gram matrix is a streamed pass of its own (every fold's at once), and
// robust Eigen-k makes one pass more per further EM iteration (kRobustEigenIterations), as
// FitStreamed does for the whole set. The neural basis is refused (trained apart).

struct FoldFitOptions {
  // Bytes the bands may hold; 0: DefaultStreamedBudget(set). Sets the band height.
  std::size_t memory_bytes = 0;
  // > 0: exactly this many rows per band (tests of band independence).
  int band_rows = 0;
  // Set: every fold is the robust fit with these options (`measured` and `progress` ignored: the
  // measured masks are found per band, MeasuredPixelMasks).
  std::optional<RobustFitOptions> robust;
  Progress* progress = nullptr;  // one phase per streamed pass, one step per band
};

// One band's fit of method `method` from fold `fold`'s fitted images. `fit` holds the band's maps
// (rows [first_row, first_row + fit.height()) of the image) and `observations` the band's selected
// pixels of every image, the intensities applied. Both are valid during the visit only.
struct FoldFit {
  std::size_t method = 0;
  std::size_t fold = 0;
  int first_row = 0;
  const Representation& fit;
  const Observations& observations;
};

// Whether VisitFoldFits streams `method`'s folds, least squares and robust: every method but the
// neural basis.
bool StreamsRobustFolds(const Method& method);

// Calls `visit` for every band of `set` (in row order) that the mask does not leave empty, for
// every method and every fold. The folds of one band and method are fitted in parallel, so
// `visit` is called from several threads at once, each with another fold (robust: each fold's
// methods in turn, so several methods at once too). Returns the band rows.
// Throws Error naming the set's source for a method that cannot be streamed or a fold with too
// few images for a method, and naming the image for a truncated or corrupt band.
int VisitFoldFits(StreamedSet& set, std::span<const Method> methods,
                  std::span<const PredictionFold> folds,
                  const std::function<void(const FoldFit&)>& visit,
                  const FoldFitOptions& options = {});

}  // namespace photomat

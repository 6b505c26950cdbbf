#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "capture/io/streamed_set.h"
#include "core/progress.h"
#include "represent/evaluation/evaluation.h"
#include "represent/stack/stack_band_reader.h"

namespace photomat {

// Evaluation of a fitted stack against its photometric set, both read band by band (README,
// "Streamed relighting and export"): Dong's eta of reconstruction (eq. 4.5.1, as
// MethodEvaluation::eta_reconstruction) of a stack too large to hold with its set. Per image, the
// sums that make e_k and sigma_k (count, sum of captured values and of their squares, sum of
// squared differences, all in double) are accumulated over the bands, so memory follows the
// band. The stack is what was fitted (it is not refitted): prediction (leave-one-out, held-out
// lights) needs fits of its own (PredictStreamed below). With ground-truth normals, the stack's
// normals (EstimateNormals of each band) are compared with the truth's rows band by band
// (NormalErrors): the same statistics as the in-memory CompareNormals, bit for bit.
struct StreamedEvaluationOptions {
  // Bytes the bands may hold (the set's band and its observation matrix, the stack's band and
  // the relit values); 0: DefaultBandBudget(kMinimumEvaluationMemory).
  std::size_t memory_bytes = 0;
  // > 0: exactly this many rows per band (tests).
  int band_rows = 0;
  bool literal_thesis_rms = false;
  // A float image of unit normals (x right, y up, z to camera) of the set's size: the result's
  // `normals` when the method gives normals.
  std::optional<std::filesystem::path> ground_truth_normals;
  Progress* progress = nullptr;  // one step per band
};
inline constexpr std::size_t kMinimumEvaluationMemory = std::size_t{16} << 20;

// eta_reconstruction and reconstruction_per_image of `stack` against `set` (from row 0; the
// mask selects the pixels), and `normals` with ground truth. Throws Error naming the stack when
// its size or output channels differ from the set's, or the truth when its size differs.
MethodEvaluation EvaluateStackStreamed(StreamedSet& set, StackBandReader& stack,
                                       const StreamedEvaluationOptions& options = {});

// EvaluateStackStreamed of several stacks of the set in one pass over its photographs (each band
// decoded once for all of them, the bands as high as the budget allows with every stack's band
// held): the evaluations in the stacks' order, each the stack's alone to double rounding (its
// sums are grouped by other bands).
std::vector<MethodEvaluation> EvaluateStacksStreamed(StreamedSet& set,
                                                     std::span<StackBandReader* const> stacks,
                                                     const StreamedEvaluationOptions& options = {});

// The ability of prediction streamed (VisitFoldFits, represent/streaming/streamed_folds.h): each
// fold of the leave-one-out (or held-out) evaluation fitted band by band, its predicted images
// relit in the band and the per-image sums of e_k, sigma_k and the PSNR (its peak the largest
// captured value) accumulated over the bands: the same eta and PSNR of prediction as
// EvaluateMethod, to float rounding, in memory for a band. Least squares or robust, every method
// but the neural basis (StreamsRobustFolds).
struct StreamedPredictionOptions {
  // Bytes the bands may hold; 0: the fit's default (DefaultStreamedBudget).
  std::size_t memory_bytes = 0;
  int band_rows = 0;  // > 0: exactly this many rows per band (tests)
  // As EvaluationOptions::hold_out_every: 0 leave-one-out, K every K-th image held out.
  int hold_out_every = 0;
  bool literal_thesis_rms = false;
  // As EvaluationOptions::robust (`measured` ignored: found per band).
  std::optional<RobustFitOptions> robust;
  // With hold_out_every > 0: also the SSIM and colour difference of every held-out image, as in
  // memory (ScorePrediction): each prediction is compared band by band
  // (MaskedDisplayComparison: about 10 rows x width x channels x 16 bytes held per held-out image
  // and method), its white, the largest captured value, found first by a pass over the held-out
  // images alone. Not for leave-one-out, where that would be every image of the set.
  bool appearance = false;
  Progress* progress = nullptr;
  // Set: every method is also fitted to all the images in the same passes (a fold more, fitting
  // every image and predicting none), and each band's fit handed here: the method's index, the
  // band's first row, its fit (valid during the call). Called in row order for each method,
  // never twice at once for one method; bands the mask leaves empty are not fitted. `evaluate
  // --stream` writes its scratch stacks from it (FittedStackWriter) instead of making a fit's
  // passes over the photographs again (the Gram pass, robust Eigen-k's EM passes).
  std::function<void(std::size_t, int, const Representation&)> whole_set_fit;
};

// Sets the method and prediction of `evaluations[i]` (prediction_images, eta_prediction,
// psnr_prediction, with `appearance` ssim_prediction and delta_e2000_prediction, and their
// per-image values) for `methods[i]` fitted to `set`. Throws Error naming the set's source when
// the sizes differ, for a method that cannot be streamed (the neural basis), a fold too small for
// a method or `appearance` with leave-one-out, and naming the image at fault for a truncated or
// corrupt one.
void PredictStreamed(StreamedSet& set, std::span<const Method> methods,
                     std::span<MethodEvaluation> evaluations,
                     const StreamedPredictionOptions& options = {});

}  // namespace photomat

#include "represent/evaluation/streamed_evaluation.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "core/error.h"
#include "core/image_band_io.h"
#include "core/memory_limits.h"
#include "represent/evaluation/image_comparison.h"
#include "represent/fitting/observations.h"
#include "represent/fitting/prediction_folds.h"
#include "represent/model/normal_error.h"
#include "represent/streaming/streamed_folds.h"

namespace photomat {
namespace {

// The sums of one image's e_k, sigma_k and PSNR over the bands so far.
struct ImageSums {
  double count = 0.0;
  double captured = 0.0;
  double captured_squared = 0.0;
  double difference_squared = 0.0;
  double peak = -INFINITY;  // the largest captured value

  // A band's captured values of the image and their relit values.
  void Add(const Eigen::VectorXd& values, const Eigen::VectorXf& relit) {
    count += static_cast<double>(values.size());
    captured += values.sum();
    captured_squared += values.squaredNorm();
    difference_squared += (relit.cast<double>() - values).squaredNorm();
    peak = std::max(peak, values.maxCoeff());
  }

  // As PeakSignalToNoiseRatio (evaluation.h).
  double Psnr() const { return PsnrDecibels(peak, difference_squared / count); }

  double NormalisedError(bool literal_thesis_rms) const {
    const double mean = captured / count;
    const double sigma = std::sqrt(std::max(0.0, captured_squared / count - mean * mean));
    return NormalisedErrorFromSums(difference_squared, count, sigma, literal_thesis_rms);
  }
};

int BandRows(const StreamedSet& set, std::span<StackBandReader* const> stacks,
             const StreamedEvaluationOptions& options) {
  // Per pixel: the set's band and its observation matrix (4 bytes x images x channels each), each
  // stack's band as stored and gathered, and the relit values of the images relit at once (one
  // per thread).
  const auto threads = static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
  std::size_t maps = 0;
  for (const StackBandReader* stack : stacks) {
    maps += static_cast<std::size_t>(stack->stored_channels() +
                                     stack->header().representation.maps().channels());
  }
  const std::size_t pixel =
      8 * static_cast<std::size_t>(set.size()) * static_cast<std::size_t>(set.channels()) +
      4 * (maps + threads * static_cast<std::size_t>(set.channels()));
  return BudgetedBandRows(options.band_rows, options.memory_bytes, kMinimumEvaluationMemory,
                          pixel * static_cast<std::size_t>(set.width()), set.height());
}

void CheckStackFitsSet(const StreamedSet& set, const StackBandReader& stack) {
  const Representation& header = stack.header().representation;
  if (stack.width() != set.width() || stack.height() != set.height() ||
      header.output_channels() != set.channels()) {
    throw Error(stack.path(),
                fmt::format("a {}x{} stack of {} channels cannot be evaluated against {}, "
                            "{}x{} with {}",
                            stack.width(), stack.height(), header.output_channels(),
                            set.source().string(), set.width(), set.height(), set.channels()));
  }
}

// One stack's reconstruction sums and normal errors over the bands so far.
struct StackSums {
  std::vector<ImageSums> images;
  NormalErrors normal_errors;
  bool gives_normals = false;
};

// Per image of `images` (indices into `set`), the white of its renderings (PredictionWhite): the
// largest value over the mask, intensities applied, as the fit's observations hold it. One pass
// over those images alone.
std::vector<double> HeldOutWhites(const StreamedSet& set, const std::vector<int>& images,
                                  const StreamedPredictionOptions& options) {
  StreamedSet held_out = set.Subset(images);
  const std::size_t pixel =
      8 * static_cast<std::size_t>(images.size()) * static_cast<std::size_t>(set.channels());
  const int band_rows =
      BudgetedBandRows(options.band_rows, options.memory_bytes, kMinimumEvaluationMemory,
                       pixel * static_cast<std::size_t>(set.width()), set.height());
  std::vector<double> largest(images.size(), -INFINITY);
  NullProgress none;
  Progress& progress = OrNull(options.progress, none);
  progress.Start("held-out whites",
                 static_cast<std::size_t>((set.height() + band_rows - 1) / band_rows));
  while (held_out.next_row() < held_out.height()) {
    const int first = held_out.next_row();
    const int rows = std::min(band_rows, held_out.height() - first);
    const PhotometricSet band = held_out.ReadBand(rows);
    progress.Advance();
    // A band set without the mask's rows selects nothing (ReadBand).
    if (held_out.SelectedPixels(first, rows) == 0) continue;
    const Observations observations(band);
    for (std::size_t j = 0; j < images.size(); ++j) {
      largest[j] = std::max(largest[j], double{observations.matrix().col(j).maxCoeff()});
    }
  }
  progress.Finish();
  std::vector<double> whites;
  for (double value : largest) whites.push_back(PredictionWhite(value));
  return whites;
}

}  // namespace

std::vector<MethodEvaluation> EvaluateStacksStreamed(StreamedSet& set,
                                                     std::span<StackBandReader* const> stacks,
                                                     const StreamedEvaluationOptions& options) {
  for (const StackBandReader* stack : stacks) CheckStackFitsSet(set, *stack);
  if (set.next_row() != 0) set.Rewind();
  for (StackBandReader* stack : stacks) {
    if (stack->next_row() != 0) stack->Rewind();
  }
  const int band_rows = BandRows(set, stacks, options);
  const int bands = (set.height() + band_rows - 1) / band_rows;
  std::optional<ImageBandReader> truth;
  if (options.ground_truth_normals) {
    truth.emplace(*options.ground_truth_normals);
    if (truth->width() != set.width() || truth->height() != set.height()) {
      throw Error(*options.ground_truth_normals,
                  fmt::format("normals are {}x{} but the images are {}x{}", truth->width(),
                              truth->height(), set.width(), set.height()));
    }
  }
  std::vector<StackSums> sums(stacks.size());
  for (StackSums& stack : sums) {
    stack.images.resize(static_cast<std::size_t>(set.size()));
    stack.gives_normals = truth.has_value();
  }
  NullProgress none;
  Progress& progress = OrNull(options.progress, none);
  progress.Start("evaluate", static_cast<std::size_t>(bands));
  for (int b = 0; b < bands; ++b) {
    const int first = set.next_row();
    const int rows = std::min(band_rows, set.height() - first);
    const PhotometricSet band = set.ReadBand(rows);
    std::optional<Image> truth_band;
    if (truth) {
      truth_band.emplace(truth->width(), rows, truth->channels());
      truth->ReadNext(truth_band->View());
    }
    // A band the mask leaves empty has normals to compare but no pixel to relight.
    std::optional<Observations> observations;
    if (set.SelectedPixels(first, rows) > 0) observations.emplace(band);
    for (std::size_t m = 0; m < stacks.size(); ++m) {
      const LoadedStack maps = stacks[m]->ReadNext(rows);
      StackSums& stack = sums[m];
      if (truth_band) {
        std::optional<Image> normals;
        if (stack.gives_normals) normals = EstimateNormals(maps.representation);
        // A method that gives none gives none in any band.
        stack.gives_normals = normals.has_value();
        // The mask's rows from the set (a band set has none where they select nothing: ReadBand).
        if (normals) stack.normal_errors.Add(*normals, *truth_band, set.MaskRows(first, rows));
      }
      if (!observations) continue;
      // Each image's sums are its own: the images are relit in parallel.
      tbb::parallel_for(0, set.size(), [&](int k) {
        const Eigen::VectorXf relit =
            RelightObservedPixels(maps.representation, *observations, band.light(k));
        stack.images[static_cast<std::size_t>(k)].Add(observations->matrix().col(k).cast<double>(),
                                                      relit);
      });
    }
    progress.Advance();
  }
  progress.Finish();
  std::vector<MethodEvaluation> results;
  for (std::size_t m = 0; m < stacks.size(); ++m) {
    MethodEvaluation& result = results.emplace_back();
    result.method = Method::Parse(stacks[m]->header().representation.method());
    double total = 0.0;
    for (const ImageSums& image : sums[m].images) {
      if (image.count == 0.0) throw Error(set.source(), "the mask selects no pixel to evaluate");
      result.reconstruction_per_image.push_back(image.NormalisedError(options.literal_thesis_rms));
      total += result.reconstruction_per_image.back();
    }
    result.eta_reconstruction = total / static_cast<double>(sums[m].images.size());
    if (sums[m].gives_normals) result.normals = sums[m].normal_errors.Summary();
  }
  return results;
}

MethodEvaluation EvaluateStackStreamed(StreamedSet& set, StackBandReader& stack,
                                       const StreamedEvaluationOptions& options) {
  StackBandReader* const one[] = {&stack};
  return std::move(EvaluateStacksStreamed(set, one, options).front());
}

void PredictStreamed(StreamedSet& set, std::span<const Method> methods,
                     std::span<MethodEvaluation> evaluations,
                     const StreamedPredictionOptions& options) {
  if (methods.size() != evaluations.size()) {
    throw Error(set.source(),
                fmt::format("{} methods but {} evaluations", methods.size(), evaluations.size()));
  }
  const std::vector<PredictionFold> folds = PredictionFolds(set.size(), options.hold_out_every);
  std::vector<PredictionFold> fitted_folds = folds;
  const std::size_t whole_set = folds.size();  // the fold of every image, when asked
  if (options.whole_set_fit) {
    PredictionFold all;
    for (int k = 0; k < set.size(); ++k) all.fitted.push_back(k);
    fitted_folds.push_back(std::move(all));
  }
  // Per method, per image of the set: each image is predicted by one fold only, so the folds
  // fitted in parallel write to different sums (and comparisons).
  std::vector<std::vector<ImageSums>> sums(methods.size(), std::vector<ImageSums>(set.size()));
  std::vector<std::vector<std::optional<MaskedDisplayComparison>>> looks(
      methods.size(), std::vector<std::optional<MaskedDisplayComparison>>(set.size()));
  if (options.appearance) {
    if (options.hold_out_every <= 0) {
      throw Error(set.source(),
                  "the SSIM and colour difference of a streamed prediction are measured for "
                  "held-out images only (--hold-out-every), not for every image of leave-one-out");
    }
    const std::vector<int>& held_out = folds.front().predicted;
    const std::vector<double> whites = HeldOutWhites(set, held_out, options);
    for (auto& method : looks) {
      for (std::size_t j = 0; j < held_out.size(); ++j) {
        method[static_cast<std::size_t>(held_out[j])].emplace(set.width(), set.height(),
                                                              set.channels(), whites[j]);
      }
    }
  }
  FoldFitOptions fits;
  fits.memory_bytes = options.memory_bytes;
  fits.band_rows = options.band_rows;
  fits.robust = options.robust;
  fits.progress = options.progress;
  VisitFoldFits(
      set, methods, fitted_folds,
      [&](const FoldFit& band) {
        if (band.fold == whole_set) {
          options.whole_set_fit(band.method, band.first_row, band.fit);
          return;
        }
        const std::vector<int>& predicted = folds[band.fold].predicted;
        tbb::parallel_for(std::size_t{0}, predicted.size(), [&](std::size_t j) {
          const int k = predicted[j];
          const Eigen::VectorXf relit = RelightObservedPixels(
              band.fit, band.observations, set.lights()[static_cast<std::size_t>(k)]);
          sums[band.method][static_cast<std::size_t>(k)].Add(
              band.observations.matrix().col(k).cast<double>(), relit);
          if (auto& look = looks[band.method][static_cast<std::size_t>(k)]) {
            const PredictionImages images = PredictionAsImages(band.observations, k, relit);
            look->AddBand(band.first_row, images.predicted, images.captured, images.selected);
          }
        });
      },
      fits);
  for (std::size_t i = 0; i < methods.size(); ++i) {
    MethodEvaluation& result = evaluations[i];
    result.method = methods[i];
    result.prediction_images.clear();
    std::vector<PredictionScores> scores;
    for (const PredictionFold& fold : folds) {
      for (int k : fold.predicted) {
        const ImageSums& image = sums[i][static_cast<std::size_t>(k)];
        if (image.count == 0.0) throw Error(set.source(), "the mask selects no pixel to evaluate");
        result.prediction_images.push_back(k);
        PredictionScores& score = scores.emplace_back();
        score.eta = image.NormalisedError(options.literal_thesis_rms);
        score.psnr = image.Psnr();
        if (auto& look = looks[i][static_cast<std::size_t>(k)]) {
          score.ssim = look->Ssim();
          score.delta_e2000 = look->MeanDeltaE2000();
        }
      }
    }
    SetPredictionScores(result, scores);
  }
}

}  // namespace photomat

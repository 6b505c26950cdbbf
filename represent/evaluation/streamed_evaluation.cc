#include "represent/evaluation/streamed_evaluation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "core/error.h"
#include "core/image_band_io.h"
#include "core/memory_limits.h"
#include "represent/fitting/observations.h"
#include "represent/model/normal_error.h"

namespace photomat {
namespace {

// The sums of one image's e_k and sigma_k over the bands so far.
struct ImageSums {
  double count = 0.0;
  double captured = 0.0;
  double captured_squared = 0.0;
  double difference_squared = 0.0;

  double NormalisedError(bool literal_thesis_rms) const {
    const double mean = captured / count;
    const double sigma = std::sqrt(std::max(0.0, captured_squared / count - mean * mean));
    const double error = literal_thesis_rms ? std::sqrt(difference_squared) / count
                                            : std::sqrt(difference_squared / count);
    if (sigma == 0.0) return error == 0.0 ? 0.0 : INFINITY;
    return error / sigma;
  }
};

int BandRows(const StreamedSet& set, const StackBandReader& stack,
             const StreamedEvaluationOptions& options) {
  if (options.band_rows > 0) return std::min(options.band_rows, set.height());
  const std::size_t memory =
      options.memory_bytes > 0 ? options.memory_bytes : DefaultBandBudget(kMinimumEvaluationMemory);
  // Per pixel: the set's band and its observation matrix (4 bytes x images x channels each), the
  // stack's band as stored and gathered, and one image's relit values.
  const std::size_t pixel =
      8 * static_cast<std::size_t>(set.size()) * static_cast<std::size_t>(set.channels()) +
      4 * static_cast<std::size_t>(stack.stored_channels() +
                                   stack.header().representation.maps().channels() +
                                   set.channels());
  const std::size_t rows = memory / std::max<std::size_t>(pixel * set.width(), 1);
  return static_cast<int>(std::clamp<std::size_t>(rows, 1, static_cast<std::size_t>(set.height())));
}

}  // namespace

MethodEvaluation EvaluateStackStreamed(StreamedSet& set, StackBandReader& stack,
                                       const StreamedEvaluationOptions& options) {
  const Representation& header = stack.header().representation;
  if (stack.width() != set.width() || stack.height() != set.height() ||
      header.output_channels() != set.channels()) {
    throw Error(stack.path(),
                fmt::format("a {}x{} stack of {} channels cannot be evaluated against {}, "
                            "{}x{} with {}",
                            stack.width(), stack.height(), header.output_channels(),
                            set.source().string(), set.width(), set.height(), set.channels()));
  }
  if (set.next_row() != 0) set.Rewind();
  if (stack.next_row() != 0) stack.Rewind();
  const int band_rows = BandRows(set, stack, options);
  const int bands = (set.height() + band_rows - 1) / band_rows;
  std::vector<ImageSums> sums(static_cast<std::size_t>(set.size()));
  std::optional<ImageBandReader> truth;
  if (options.ground_truth_normals) {
    truth.emplace(*options.ground_truth_normals);
    if (truth->width() != set.width() || truth->height() != set.height()) {
      throw Error(*options.ground_truth_normals,
                  fmt::format("normals are {}x{} but the images are {}x{}", truth->width(),
                              truth->height(), set.width(), set.height()));
    }
  }
  NormalErrors normal_errors;
  bool gives_normals = truth.has_value();
  NullProgress none;
  Progress& progress = OrNull(options.progress, none);
  progress.Start("evaluate", static_cast<std::size_t>(bands));
  for (int b = 0; b < bands; ++b) {
    const int first = set.next_row();
    const int rows = std::min(band_rows, set.height() - first);
    const PhotometricSet band = set.ReadBand(rows);
    const LoadedStack maps = stack.ReadNext(rows);
    if (truth) {
      Image truth_band(truth->width(), rows, truth->channels());
      truth->ReadNext(truth_band.View());
      std::optional<Image> normals;
      if (gives_normals) normals = EstimateNormals(maps.representation);
      gives_normals = normals.has_value();  // a method that gives none gives none in any band
      // The mask's rows from the set (a band set has none where they select nothing: ReadBand).
      if (normals) normal_errors.Add(*normals, truth_band, set.MaskRows(first, rows));
    }
    if (set.SelectedPixels(first, rows) == 0) {
      progress.Advance();
      continue;
    }
    const Observations observations(band);
    for (int k = 0; k < set.size(); ++k) {
      const Eigen::VectorXf relit =
          RelightObservedPixels(maps.representation, observations, band.light(k));
      const auto captured = observations.matrix().col(k).cast<double>();
      ImageSums& image = sums[static_cast<std::size_t>(k)];
      image.count += static_cast<double>(captured.size());
      image.captured += captured.sum();
      image.captured_squared += captured.squaredNorm();
      image.difference_squared += (relit.cast<double>() - captured).squaredNorm();
    }
    progress.Advance();
  }
  progress.Finish();
  MethodEvaluation result;
  result.method = Method::Parse(header.method());
  double total = 0.0;
  for (const ImageSums& image : sums) {
    if (image.count == 0.0) throw Error(set.source(), "the mask selects no pixel to evaluate");
    result.reconstruction_per_image.push_back(image.NormalisedError(options.literal_thesis_rms));
    total += result.reconstruction_per_image.back();
  }
  result.eta_reconstruction = total / static_cast<double>(sums.size());
  if (gives_normals) result.normals = normal_errors.Summary();
  return result;
}

}  // namespace photomat

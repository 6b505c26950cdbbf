#include "represent/evaluation/evaluation.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"
#include "represent/evaluation/image_comparison.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/prediction_folds.h"

namespace photomat {
namespace {

double Mean(const std::vector<double>& values) {
  return std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
}

}  // namespace

double NormalisedErrorFromSums(double squared_difference, double count, double sigma,
                               bool literal_thesis_rms) {
  const double error = literal_thesis_rms ? std::sqrt(squared_difference) / count
                                          : std::sqrt(squared_difference / count);
  if (sigma == 0.0) return error == 0.0 ? 0.0 : INFINITY;
  return error / sigma;
}

double PsnrDecibels(double peak, double mean_squared_error) {
  if (mean_squared_error == 0.0) return INFINITY;
  return 10.0 * std::log10(peak * peak / mean_squared_error);
}

double NormalisedRmsError(const Observations& observations, int image, const Eigen::VectorXf& relit,
                          bool literal_thesis_rms) {
  const auto captured = observations.matrix().col(image).cast<double>();
  const auto count = static_cast<double>(captured.size());
  const double mean = captured.mean();
  const double sigma = std::sqrt((captured.array() - mean).square().sum() / count);
  return NormalisedErrorFromSums((relit.cast<double>() - captured).squaredNorm(), count, sigma,
                                 literal_thesis_rms);
}

double PeakSignalToNoiseRatio(const Observations& observations, int image,
                              const Eigen::VectorXf& relit) {
  const auto captured = observations.matrix().col(image).cast<double>();
  return PsnrDecibels(captured.maxCoeff(),
                      (relit.cast<double>() - captured).squaredNorm() / captured.size());
}

double PredictionWhite(double largest_captured) {
  return largest_captured > 0.0 ? largest_captured : 1.0;
}

PredictionImages PredictionAsImages(const Observations& observations, int image,
                                    const Eigen::VectorXf& relit) {
  const int width = observations.width(), height = observations.height();
  const int channels = observations.channels();
  PredictionImages out{Image(width, height, channels), Image(width, height, channels),
                       Mask(width, height, false)};
  const std::vector<std::size_t>& pixels = observations.pixel_indices();
  for (std::size_t p : pixels) out.selected.Set(p, true);
  const auto column = observations.matrix().col(image);
  const std::size_t m = pixels.size();
  for (int c = 0; c < channels; ++c) {
    const auto predicted = out.predicted.plane(c);
    const auto captured = out.captured.plane(c);
    for (std::size_t k = 0; k < m; ++k) {
      const auto row = static_cast<Eigen::Index>(c * m + k);
      predicted[pixels[k]] = relit[row];
      captured[pixels[k]] = column[row];
    }
  }
  return out;
}

PredictionScores ScorePrediction(const Observations& observations, int image,
                                 const Eigen::VectorXf& relit, bool literal_thesis_rms,
                                 bool appearance) {
  PredictionScores scores;
  scores.eta = NormalisedRmsError(observations, image, relit, literal_thesis_rms);
  scores.psnr = PeakSignalToNoiseRatio(observations, image, relit);
  if (!appearance) return scores;
  const double white = PredictionWhite(observations.matrix().col(image).maxCoeff());
  const PredictionImages images = PredictionAsImages(observations, image, relit);
  const DisplayedComparison displayed =
      CompareDisplayed(images.predicted, images.captured, images.selected, white);
  scores.ssim = displayed.ssim;
  scores.delta_e2000 = displayed.mean_delta_e2000;
  return scores;
}

void SetPredictionScores(MethodEvaluation& evaluation,
                         const std::vector<PredictionScores>& scores) {
  if (scores.size() != evaluation.prediction_images.size()) {
    throw Error(fmt::format("{} prediction scores for {} predicted images", scores.size(),
                            evaluation.prediction_images.size()));
  }
  evaluation.prediction_per_image.clear();
  evaluation.psnr_prediction_per_image.clear();
  evaluation.ssim_prediction_per_image.clear();
  evaluation.delta_e2000_prediction_per_image.clear();
  for (const PredictionScores& image : scores) {
    evaluation.prediction_per_image.push_back(image.eta);
    evaluation.psnr_prediction_per_image.push_back(image.psnr);
    if (image.ssim) evaluation.ssim_prediction_per_image.push_back(*image.ssim);
    if (image.delta_e2000) {
      evaluation.delta_e2000_prediction_per_image.push_back(*image.delta_e2000);
    }
  }
  evaluation.eta_prediction = Mean(evaluation.prediction_per_image);
  evaluation.psnr_prediction = Mean(evaluation.psnr_prediction_per_image);
  // A measure some images lack is left out whole.
  const auto set_mean = [&](std::vector<double>& per_image, std::optional<double>& mean) {
    mean.reset();
    if (per_image.size() == scores.size() && !scores.empty()) {
      mean = Mean(per_image);
    } else {
      per_image.clear();
    }
  };
  set_mean(evaluation.ssim_prediction_per_image, evaluation.ssim_prediction);
  set_mean(evaluation.delta_e2000_prediction_per_image, evaluation.delta_e2000_prediction);
}

Eigen::VectorXf RelightObservedPixels(const Representation& representation,
                                      const Observations& observations,
                                      const LightDirection& light) {
  const Eigen::VectorXf coefficients = representation.basis().Coefficients(light).cast<float>();
  const Eigen::Index m = observations.pixels();
  const int channels = observations.channels();
  Eigen::VectorXf relit(m * channels);
  std::vector<float> out(channels);
  for (Eigen::Index k = 0; k < m; ++k) {
    representation.RelightPixel(representation.maps().pixel(observations.pixel_indices()[k]),
                                coefficients, out);
    for (int c = 0; c < channels; ++c) relit[c * m + k] = out[c];
  }
  return relit;
}

MethodEvaluation EvaluateMethod(const PhotometricSet& set, const Observations& observations,
                                const Method& method, const Image* truth,
                                const EvaluationOptions& options) {
  MethodEvaluation result;
  result.method = method;
  const int n = set.size();
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);

  // The least-squares fit, or the robust one (without a progress bar inside the parallel folds).
  const auto fit = [&](std::span<const int> selected, Progress* robust_progress) {
    if (!options.robust) {
      return FitObservations(observations, set.lights(), method, selected, set.source());
    }
    RobustFitOptions robust = *options.robust;
    robust.progress = robust_progress;
    return RobustFit(observations, set.lights(), selected, robust, set.source()).Fit(method);
  };
  const Representation full = fit(all, options.progress);
  result.reconstruction_per_image.resize(n);
  tbb::parallel_for(0, n, [&](int k) {
    result.reconstruction_per_image[k] =
        NormalisedRmsError(observations, k, RelightObservedPixels(full, observations, set.light(k)),
                           options.literal_thesis_rms);
  });
  result.eta_reconstruction = Mean(result.reconstruction_per_image);
  if (truth) {
    if (const auto normals = EstimateNormals(full)) {
      result.normals = CompareNormals(*normals, *truth, set.MaskOrAll());
    }
  }
  if (!options.prediction) return result;

  // Each fold's fit predicts its images: leave-one-out one fit per image, run in parallel; held
  // out, one fit for all the predicted images.
  const std::vector<PredictionFold> folds = PredictionFolds(n, options.hold_out_every);
  CheckFoldsFit(folds, method, set.source());
  std::vector<std::size_t> offsets;  // per fold, its first entry of prediction_images
  for (const PredictionFold& fold : folds) {
    offsets.push_back(result.prediction_images.size());
    result.prediction_images.insert(result.prediction_images.end(), fold.predicted.begin(),
                                    fold.predicted.end());
  }
  std::vector<PredictionScores> scores(result.prediction_images.size());
  progress.Start(fmt::format("{} {}", options.hold_out_every > 0 ? "held-out" : "leave-one-out",
                             method.Name()),
                 folds.size());
  tbb::parallel_for(std::size_t{0}, folds.size(), [&](std::size_t f) {
    const PredictionFold& fold = folds[f];
    const Representation fold_fit = fit(fold.fitted, nullptr);
    const std::size_t first = offsets[f];
    tbb::parallel_for(std::size_t{0}, fold.predicted.size(), [&](std::size_t j) {
      const int k = fold.predicted[j];
      scores[first + j] = ScorePrediction(
          observations, k, RelightObservedPixels(fold_fit, observations, set.light(k)),
          options.literal_thesis_rms, options.appearance);
    });
    progress.Advance();
  });
  progress.Finish();
  SetPredictionScores(result, scores);
  return result;
}

nlohmann::json MethodEvaluation::ToJson() const {
  nlohmann::json json = {{"eta_reconstruction", eta_reconstruction},
                         {"eta_reconstruction_per_image", reconstruction_per_image}};
  if (eta_prediction) {
    json["eta_prediction"] = *eta_prediction;
    json["eta_prediction_per_image"] = prediction_per_image;
    json["prediction_images"] = prediction_images;
    if (psnr_prediction) {
      json["psnr_prediction"] = *psnr_prediction;
      json["psnr_prediction_per_image"] = psnr_prediction_per_image;
    }
    if (ssim_prediction) {
      json["ssim_prediction"] = *ssim_prediction;
      json["ssim_prediction_per_image"] = ssim_prediction_per_image;
    }
    if (delta_e2000_prediction) {
      json["delta_e2000_prediction"] = *delta_e2000_prediction;
      json["delta_e2000_prediction_per_image"] = delta_e2000_prediction_per_image;
    }
  }
  if (normals) json["normals"] = normals->ToJson();
  return json;
}

nlohmann::json EvaluationsToJson(const std::vector<MethodEvaluation>& evaluations) {
  nlohmann::json json = nlohmann::json::object();
  for (const auto& evaluation : evaluations) json[evaluation.method.Name()] = evaluation.ToJson();
  return json;
}

}  // namespace photomat

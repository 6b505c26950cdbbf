#include "represent/evaluation/evaluation.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"
#include "represent/fitting/fit.h"

namespace photomat {
namespace {

double Mean(const std::vector<double>& values) {
  return std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
}

}  // namespace

nlohmann::json NormalErrorStats::ToJson() const {
  return {{"pixels", pixels},
          {"mean_angular_error_deg", mean_degrees},
          {"median_angular_error_deg", median_degrees},
          {"max_angular_error_deg", max_degrees},
          {"fraction_below_5_deg", fraction_below_5_degrees},
          {"fraction_below_10_deg", fraction_below_10_degrees}};
}

NormalErrorStats CompareNormals(const Image& estimated, const Image& truth, const Mask& mask) {
  if (estimated.width() != truth.width() || estimated.height() != truth.height()) {
    throw Error(fmt::format("ground-truth normals are {}x{} but the estimate is {}x{}",
                            truth.width(), truth.height(), estimated.width(), estimated.height()));
  }
  if (estimated.channels() < 3 || truth.channels() < 3) {
    throw Error("normal maps need 3 channels (x, y, z)");
  }
  std::vector<double> errors;
  for (std::size_t p = 0; p < truth.pixel_count(); ++p) {
    if (mask.width() == truth.width() && !mask[p]) continue;
    const auto t = truth.pixel(p);
    const auto e = estimated.pixel(p);
    const Eigen::Vector3d tv(t[0], t[1], t[2]), ev(e[0], e[1], e[2]);
    if (tv.squaredNorm() < 0.25 || ev.squaredNorm() == 0.0) continue;  // outside the truth
    errors.push_back(AngleBetweenDegrees(tv, ev));
  }
  if (errors.empty()) throw Error("no pixel has both a ground-truth and an estimated normal");
  NormalErrorStats stats;
  stats.pixels = errors.size();
  stats.mean_degrees = Mean(errors);
  const auto count_below = [&](double limit) {
    return static_cast<double>(
               std::count_if(errors.begin(), errors.end(), [&](double e) { return e < limit; })) /
           errors.size();
  };
  stats.fraction_below_5_degrees = count_below(5.0);
  stats.fraction_below_10_degrees = count_below(10.0);
  std::sort(errors.begin(), errors.end());
  const std::size_t n = errors.size();
  stats.median_degrees = n % 2 ? errors[n / 2] : 0.5 * (errors[n / 2 - 1] + errors[n / 2]);
  stats.max_degrees = errors.back();
  return stats;
}

double NormalisedRmsError(const Observations& observations, int image, const Eigen::VectorXf& relit,
                          bool literal_thesis_rms) {
  const auto captured = observations.matrix().col(image).cast<double>();
  const auto count = static_cast<double>(captured.size());
  const double mean = captured.mean();
  const double sigma = std::sqrt((captured.array() - mean).square().sum() / count);
  const double squared = (relit.cast<double>() - captured).squaredNorm();
  const double error = literal_thesis_rms ? std::sqrt(squared) / count : std::sqrt(squared / count);
  if (sigma == 0.0) return error == 0.0 ? 0.0 : INFINITY;
  return error / sigma;
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

  progress.Start(fmt::format("leave-one-out {}", method.Name()), n);
  result.prediction_per_image.resize(n);
  tbb::parallel_for(0, n, [&](int k) {
    std::vector<int> others;
    for (int i = 0; i < n; ++i) {
      if (i != k) others.push_back(i);
    }
    const Representation fold = fit(others, nullptr);
    result.prediction_per_image[k] =
        NormalisedRmsError(observations, k, RelightObservedPixels(fold, observations, set.light(k)),
                           options.literal_thesis_rms);
    progress.Advance();
  });
  progress.Finish();
  result.eta_prediction = Mean(result.prediction_per_image);
  return result;
}

nlohmann::json MethodEvaluation::ToJson() const {
  nlohmann::json json = {{"eta_reconstruction", eta_reconstruction},
                         {"eta_reconstruction_per_image", reconstruction_per_image}};
  if (eta_prediction) {
    json["eta_prediction"] = *eta_prediction;
    json["eta_prediction_per_image"] = prediction_per_image;
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

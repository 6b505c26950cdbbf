#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "core/image.h"
#include "core/photometric_set.h"
#include "core/progress.h"
#include "represent/fitting/observations.h"
#include "represent/fitting/robust_fit.h"
#include "represent/model/method.h"
#include "represent/model/normal_error.h"
#include "represent/model/representation.h"

namespace photomat {

struct EvaluationOptions {
  // Leave-one-out ability-of-prediction (one fit per image); off: reconstruction only.
  bool prediction = true;
  // > 0: instead of leave-one-out, one fit without the held-out images i % hold_out_every == 0
  // (every k-th light from the first), which predicts each held-out image: one fit per method
  // instead of one per image, for slow fits (pbr) and for a test set of unseen lights.
  int hold_out_every = 0;
  // The thesis's eq. 4.5.1 as printed, e_k = (1/NM) sqrt(sum (r - i)^2), instead of the RMS
  // sqrt((1/NM) sum (r - i)^2) that the reading in the spec reconstructs.
  bool literal_thesis_rms = false;
  Progress* progress = nullptr;
  // Set: every fit (the full one and each leave-one-out fold) is the robust fit with these
  // options (represent/robust_fit.h); the errors are still measured against every observation.
  std::optional<RobustFitOptions> robust;
};

struct MethodEvaluation {
  Method method;
  // Dong's normalised RMS error (eq. 4.5.1): the mean over images of e_k / sigma_k, e_k the RMS of
  // relit minus captured over the mask's pixels and all channels, sigma_k the standard deviation
  // of captured image k over the same values.
  double eta_reconstruction = 0.0;       // fitted from all images, relit at each of them
  std::optional<double> eta_prediction;  // image k relit from a fit without image k
  // The peak signal-to-noise ratio of the predicted images, 10 log10(peak^2 / MSE) in dB, peak
  // the largest captured value of image k over the mask's pixels and channels (the images are
  // linear and not scaled to a fixed range); the mean over the predicted images.
  std::optional<double> psnr_prediction;
  std::vector<double> reconstruction_per_image;
  // Per predicted image, in the order of prediction_images (every image for leave-one-out, the
  // held-out ones for EvaluationOptions::hold_out_every).
  std::vector<int> prediction_images;
  std::vector<double> prediction_per_image;
  std::vector<double> psnr_prediction_per_image;
  std::optional<NormalErrorStats> normals;  // methods that give normals, when truth is given
  nlohmann::json ToJson() const;
};

// Dong's e_k / sigma_k from the sum of squared differences of `count` values and sigma, the
// standard deviation of the captured ones: e_k is their RMS, sqrt(sum / count), or with
// `literal_thesis_rms` eq. 4.5.1 as printed, sqrt(sum) / count. 0 for an exact relighting of a
// constant image, infinite for an inexact one. The one formula of the in-memory and streamed
// evaluations.
double NormalisedErrorFromSums(double squared_difference, double count, double sigma,
                               bool literal_thesis_rms);

// 10 log10(peak^2 / mse) in dB; infinite for an MSE of 0. The one formula of every PSNR here.
double PsnrDecibels(double peak, double mean_squared_error);

// The per-image error e_k / sigma_k of `relit` values against column `image` of `observations`
// (the rows of the selected pixels).
double NormalisedRmsError(const Observations& observations, int image, const Eigen::VectorXf& relit,
                          bool literal_thesis_rms = false);

// The PSNR in dB of `relit` values against column `image` of `observations` (see
// MethodEvaluation::psnr_prediction); infinite for an exact prediction.
double PeakSignalToNoiseRatio(const Observations& observations, int image,
                              const Eigen::VectorXf& relit);

// Relit values of `representation` under `light` at the observations' pixels, in their row order.
Eigen::VectorXf RelightObservedPixels(const Representation& representation,
                                      const Observations& observations,
                                      const LightDirection& light);

// Evaluates one method on `set` (its mask selects the pixels). `truth` holds unit normals
// (channels 0..2) in the lights' frame, or is null.
MethodEvaluation EvaluateMethod(const PhotometricSet& set, const Observations& observations,
                                const Method& method, const Image* truth,
                                const EvaluationOptions& options = {});

// The JSON of `photomat evaluate --json`: an object keyed by method name.
nlohmann::json EvaluationsToJson(const std::vector<MethodEvaluation>& evaluations);

}  // namespace photomat

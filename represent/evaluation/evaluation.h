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
  // The predictions' SSIM and colour difference (PredictionScores) too. They cost about as much
  // as the folds' fits of a cheap method (DiLiGenT cat, leave-one-out of Gradient, PTM and HSH9:
  // 4 s without, 10 s with), so `evaluate` asks for them where few images are predicted
  // (--hold-out-every) or where they are asked for (README, "Evaluation").
  bool appearance = true;
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
  // How the predicted images look beside the captured ones (ScorePrediction): the mean over the
  // predicted images of the SSIM of their sRGB renderings and of their CIEDE2000 colour
  // difference (the latter for one- or three-channel sets only), and the per-image values in the
  // order of prediction_images. Set by the in-memory evaluations (EvaluateMethod, the neural
  // basis's); the streamed ones leave them unset (README, "Evaluation").
  std::optional<double> ssim_prediction;
  std::optional<double> delta_e2000_prediction;
  std::vector<double> ssim_prediction_per_image;
  std::vector<double> delta_e2000_prediction_per_image;
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

// Every score of one predicted image: `relit` values against column `image` of `observations`.
struct PredictionScores {
  double eta = 0.0;   // NormalisedRmsError
  double psnr = 0.0;  // PeakSignalToNoiseRatio
  // With `appearance`: MaskedSsim and MaskedMeanDeltaE2000 (image_comparison.h) of the two as
  // images of the observations' size, over their selected pixels. IMPLEMENTER CHOICE: the white
  // of the renderings is the PSNR's peak, the largest captured value of the image over the
  // selected pixels (1 if that is not positive), so that all three measures use one white and
  // none depends on the set's scale (8 or 16 bits, light intensities divided out or not). The
  // colour difference is left unset for images of other than one (grey) or three (RGB) channels.
  std::optional<double> ssim;
  std::optional<double> delta_e2000;
};
// The white of the renderings ScorePrediction compares: the largest captured value of the
// image over the selected pixels, or 1 if that is not positive.
double PredictionWhite(double largest_captured);

// Column `image` of `observations` and `relit` (rows in the observations' layout) as images of
// the observations' size, 0 outside the selected pixels, and the mask of those pixels: what the
// comparisons of image_comparison.h take.
struct PredictionImages {
  Image predicted, captured;
  Mask selected;
};
PredictionImages PredictionAsImages(const Observations& observations, int image,
                                    const Eigen::VectorXf& relit);

PredictionScores ScorePrediction(const Observations& observations, int image,
                                 const Eigen::VectorXf& relit, bool literal_thesis_rms = false,
                                 bool appearance = true);

// Sets the prediction's per-image lists of `evaluation` from `scores` (in the order of
// prediction_images, which must have their count) and their means: eta, PSNR and, when every
// image has them, the SSIM and the colour difference.
void SetPredictionScores(MethodEvaluation& evaluation, const std::vector<PredictionScores>& scores);

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

#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "core/image.h"
#include "core/light_direction.h"
#include "core/photometric_set.h"
#include "core/progress.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/observations.h"
#include "represent/fitting/pbr_fit.h"
#include "represent/model/method.h"
#include "represent/model/representation.h"

namespace photomat {

// Robust photometric stereo and robust variants of the PTM and Eigen-k fits.
//
// Real captures break the Lambertian least-squares model in a few pixels of every image: attached
// and cast shadows (values far below the model), specular highlights (far above) and clipped
// samples (not measurements at all). The robust fit gives every observation (pixel k, image i) a
// weight in [0, 1] from a per-pixel robust Lambertian fit, then fits any method by weighted least
// squares with those weights: the outlier weights are shared, so PTM and Eigen-k ignore exactly
// the observations photometric stereo rejected.
//
// Per pixel (IMPLEMENTER CHOICE, README "Robust fitting"):
//   1. clipped or under-exposed observations (RobustFitOptions::measured) take no part;
//   2. the rank window: of the measured observations sorted by channel-sum intensity, the darkest
//      quarter (shadows, inter-reflection) and the brightest 40 % (specular lobes, which on real
//      materials are broad rather than sparse) are left out of the normal fit;
//   3. iteratively reweighted least squares (IRLS: Eigen 3x3 solves) over the window with the
//      chosen loss on the residuals over the window's robust residual scale (1.4826 x median
//      absolute residual); observations the current normal puts in attached shadow (n.l below
//      `attached_shadow_cosine`) get weight 0. The albedo of each channel follows along the
//      normal from the same weights;
//   4. the shared outlier weights judge every measured observation against that robust
//      Lambertian model with the same loss (scale from all of them): 0 in attached shadow and for
//      clipped samples, small for cast shadows and highlights, near 1 for the rest.
// The window fractions were measured on DiLiGenT ball and cat (README, "Robust fitting"): the
// mean error is flat within 0.2 degree for dark 0.2..0.3 and bright 0.3..0.4.
// IRLS with Eigen is what photomat uses: bench/robust_fit_table measures it against Ceres Solver
// on the same per-pixel problems.

enum class RobustLoss {
  kHuber,   // quadratic near 0, linear beyond the scale: never rejects, only down-weights
  kCauchy,  // log(1 + r^2): weights fall as 1 / r^2, smooth (the default)
  kTukey,   // biweight: weight 0 beyond the scale (hard rejection, needs a good start)
};
std::string_view ToString(RobustLoss loss);
// "huber", "cauchy", "tukey" (any case); nullopt otherwise.
std::optional<RobustLoss> ParseRobustLoss(std::string_view name);
// The IRLS weight w(u) = rho'(u) / u of a residual u already divided by the loss's scale.
double RobustWeight(RobustLoss loss, double u);
// The usual 95 %-efficiency tuning constant of each loss, in units of the residual's standard
// deviation: Huber 1.345, Cauchy 2.385, Tukey 4.685.
double DefaultLossScale(RobustLoss loss);

struct RobustFitOptions {
  RobustLoss loss = RobustLoss::kCauchy;
  // Tuning constant in units of the pixel's robust residual scale (1.4826 x the median absolute
  // residual); 0 means DefaultLossScale(loss).
  double loss_scale = 0.0;
  // The normal fit leaves out this fraction of each pixel's darkest and brightest measured
  // observations (the rank window).
  double dark_fraction = 0.25;
  double bright_fraction = 0.4;
  // An observation whose model shading n.l is below this is in (or at the edge of) attached
  // shadow, where the clamped Lambertian model is not linear: weight 0.
  double attached_shadow_cosine = 0.05;
  // The residual scale is at least this fraction of the pixel's albedo (so that a perfectly
  // Lambertian pixel does not reject its noise).
  double minimum_relative_scale = 0.01;
  int max_iterations = 20;
  // Per image, the pixels that are measurements (not clipped, not under-exposed), e.g. from
  // calibrate's MeasuredPixelMasks; empty: every pixel of every image. Not owned: the masks must
  // outlive the fit's constructor.
  std::span<const Mask> measured;
  // Not owned; used by the constructor and by Fit(pbr), so it must outlive both.
  Progress* progress = nullptr;
  // The `pbr` method's fit, started from this robust fit's normals and albedo.
  PbrFitOptions pbr;
  // The set's near lamps (PhotometricSet::near_lighting), for the pbr fit only (every other
  // method uses the lights' distant directions); null: distant lights. Not owned: must outlive
  // Fit(pbr). FitRobust takes the set's.
  const NearLighting* near_lighting = nullptr;

  nlohmann::json ToJson() const;
};

// What the weights say about the capture.
struct RobustFitSummary {
  std::size_t observations = 0;         // pixels x selected images
  std::size_t not_measured = 0;         // clipped or under-exposed (weight 0)
  std::size_t attached_shadow = 0;      // n.l below the limit (weight 0)
  std::size_t down_weighted = 0;        // weight below 0.5 from the loss
  double mean_weight = 0.0;             // shared outlier weight, over all observations
  double normal_inlier_fraction = 0.0;  // observations the normals were fitted from

  // `other`'s observations added (a streamed fit's bands): counts add, the means weigh by the
  // observations.
  void Add(const RobustFitSummary& other);
  nlohmann::json ToJson() const;
  // From ToJson's object; throws nlohmann::json's errors on another.
  static RobustFitSummary FromJson(const nlohmann::json& json);
};

// EM iterations of the weighted low-rank approximation (robust Eigen-k). The reconstruction
// error of the imputed entries changes by under 1e-3 (relative) after 8 on DiLiGenT.
inline constexpr int kRobustEigenIterations = 8;

// The robust Lambertian fit of a set of observations and its outlier weights; fits any method
// with them. Thread-compatible; Fit() is const.
class RobustFit {
 public:
  // Fits the images in `selected` (all images of `lights` belong to `observations`' columns).
  // Throws Error naming `source` for coplanar lights, fewer than 3 images, or `measured` masks of
  // the wrong count or size.
  RobustFit(const Observations& observations, const std::vector<LightDirection>& lights,
            std::span<const int> selected, const RobustFitOptions& options,
            std::filesystem::path source = {});

  // pixels x images weights in [0, 1]; 0 for images not selected.
  const Eigen::MatrixXf& weights() const { return weights_; }
  // Per selected pixel (observation row order), the unit normal (3 x pixels) and the albedo of
  // each channel along it (channels x pixels).
  const Eigen::Matrix3Xf& normals() const { return normals_; }
  const Eigen::MatrixXf& albedo() const { return albedo_; }
  const RobustFitSummary& summary() const { return summary_; }

  // `method` fitted by weighted least squares with the shared weights: gradient (the robust
  // normals, albedo per channel along them), ptm and ptm-lrgb (weighted per-pixel polynomials),
  // eigenK (weighted low-rank approximation by EM imputation), rbf and bilinear (their fit on the
  // observations with the robust Lambertian model imputed where the weights distrust the data,
  // the first step of Eigen-k's EM). 3i has no robust form (it uses
  // three images whole) and is fitted as usual; pbr: the Ceres microfacet fit (pbr_fit.h) from the
  // robust normals and albedo. The representation's details record "robust".
  Representation Fit(const Method& method) const;

  // Robust Eigen-k's steps, for fits that stream the EM iterations band by band (each iteration's
  // basis needs the Gram matrix of the whole imputed matrix). The imputed matrix has
  // Observations' rows and one column per selected image. Iteration t's basis comes from the
  // Gram matrix of the imputed matrix after t imputations (EigenBasisFromGram); after
  // kRobustEigenIterations the basis images are the imputed matrix times V.
  // The start: the data where the weights trust it, the robust Lambertian model elsewhere
  // (w * observed + (1 - w) * albedo max(0, n.l)); rbf and bilinear fit on it too.
  Eigen::MatrixXf EigenStart() const;
  // One EM step: the data where trusted, the rank-k model (filled V V^T) elsewhere.
  void EigenImpute(Eigen::MatrixXf& filled, const Eigen::MatrixXd& v) const;
  // The representation in the last iteration's basis.
  Representation EigenFromImputed(const Eigen::MatrixXf& filled, const EigenBasis& basis) const;

 private:
  Representation FitGradient() const;
  Representation FitPtm(bool lrgb) const;
  Representation FitHsh(int terms) const;
  // Weighted least squares of per-light basis terms (PTM, HSH); `lrgb`: one luminance fit times
  // a per-channel chroma, as PTM's LRGB form.
  Representation FitBasisTerms(std::shared_ptr<const LightBasis> basis, const std::string& method,
                               const std::string& prefix, bool lrgb) const;
  Representation FitEigen(int k) const;
  Representation FitLightProfileMethod(const Method& method) const;

  const Observations& observations_;
  const std::vector<LightDirection>& lights_;
  std::vector<int> selected_;
  RobustFitOptions options_;
  std::filesystem::path source_;
  Eigen::MatrixXf weights_;
  Eigen::Matrix3Xf normals_;
  Eigen::MatrixXf albedo_;
  RobustFitSummary summary_;
};

// One robust fit of `set` (its mask selects the pixels).
Representation FitRobust(const PhotometricSet& set, const Method& method,
                         const RobustFitOptions& options = {});

}  // namespace photomat

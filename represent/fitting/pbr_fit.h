#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/light_direction.h"
#include "core/near_light.h"
#include "core/progress.h"
#include "represent/fitting/observations.h"
#include "represent/model/representation.h"

namespace photomat {

// The `pbr` fit: per pixel, the microfacet maps of represent/model/shading.h (base colour,
// perceptual roughness, grey F0, normal; core/microfacet_brdf.h) by nonlinear least squares with
// Ceres: all of a pixel's observations in one residual block with hand-derived Jacobians, under a
// Cauchy loss per observation (pbr_pixel_cost.h), so that cast shadows and other gross outliers
// lose their pull; clipped samples are left out through the robust fit's measured masks. Bounds:
// base colour >= 0, roughness in [min_roughness, 1], F0 in [0, 1], a scalar that settles on its
// bound held there (pbr_fit.cc, PinOnBound); the normal lives on the unit sphere (Ceres'
// SphereManifold). Start: the robust photometric-stereo normal and albedo (RobustFit), roughness
// and F0 from a grid (grid_start) or start_roughness and start_f0. Lights: the capture's distant
// directions, or, for a capture with near lamps (`calibrate apply --near-lights`), each pixel's
// own direction to each lamp and its relative irradiance (core/near_light.h). Pixels in
// parallel (TBB), each solved alone on one thread: the result does not depend on the schedule.
struct PbrFitOptions {
  // The start of roughness and F0: the best pair of a grid (pbr_fit.cc, GridStart) at the start
  // normal, with the base colour solved for each; false: start_roughness and start_f0.
  bool grid_start = true;
  double start_roughness = 0.5;
  double start_f0 = 0.04;
  // GGX's peak grows as 1 / roughness^4: the floor keeps a pixel whose lights miss its lobe from
  // collapsing into an infinitely sharp, invisible one.
  double min_roughness = 0.05;
  // Cauchy scale, as a fraction of the pixel's brightness (mean start albedo over channels).
  double loss_scale = 0.1;
  // Regularisation of pixels whose lights never sample the specular lobe (no measured light's
  // half vector inside the lobe's half maximum at the fitted normal and roughness): they are
  // fitted again with residuals prior_weight * brightness * sqrt(observations) * (roughness -
  // prior_roughness) and the same for F0 - prior_f0. 0: off (their roughness and F0 are then
  // whatever the data leave them).
  double prior_weight = 0.0;
  double prior_roughness = 0.5;
  double prior_f0 = 0.04;
  int max_iterations = 100;

  nlohmann::json ToJson() const;
};

// Whether `light` is inside the lobe's half maximum, D(n.h) >= D(1) / 2, for a unit `normal`.
bool InSpecularLobe(const Eigen::Vector3d& normal, const Eigen::Vector3d& light, double roughness);

// Fits the images in `selected` of `observations` (3 channels); `start_normals` (3 x pixels) and
// `start_albedo` (3 x pixels) per observation row; `measured` as RobustFitOptions::measured.
// `near_lighting` (null: distant `lights`) gives the lamps of the observations' images, its frame
// the observations' (their rows from its first_row). `details` are kept (the robust fit's), with
// "pbr" (the options), "pbr_summary" (pixels, lobe_sampled, lobe_unsampled, regularised,
// mean_final_cost) and "pbr_light_model" ("near" or "distant") added. Throws Error naming
// `source` for grey images, lamps not one per light, or a build without Ceres.
Representation FitPbr(const Observations& observations, const std::vector<LightDirection>& lights,
                      const NearLighting* near_lighting, std::span<const int> selected,
                      const Eigen::Matrix3Xf& start_normals, const Eigen::MatrixXf& start_albedo,
                      std::span<const Mask> measured, const PbrFitOptions& options,
                      nlohmann::json details, const std::filesystem::path& source = {},
                      Progress* progress = nullptr);

}  // namespace photomat

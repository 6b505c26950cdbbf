#pragma once

#include <Eigen/Core>

#include "core/image.h"
#include "represent/model/representation.h"
#include "synthesize/surface/fem.h"

namespace photomat {

// Flat materials from patterns grown on a periodic grid (FemDomain::PeriodicGrid): the field as a
// tileable image, and the field used as a height map turned into a relightable material.

// The field as a width x height single-channel image named `channel` (node x + width * y is pixel
// (x, y), row 0 at the top).
Image GridFieldImage(const GridShape& grid, const Eigen::VectorXd& field,
                     const std::string& channel = "Y");

struct PatternMaterialOptions {
  // Height of the pattern's full range, in pixels (the slopes scale with it).
  double relief_pixels = 3.0;
  // Albedo (linear RGB) where the field is lowest and highest, blended linearly between.
  Eigen::Vector3f low_albedo = Eigen::Vector3f(0.75f, 0.62f, 0.45f);
  Eigen::Vector3f high_albedo = Eigen::Vector3f(0.18f, 0.12f, 0.08f);
  // Raise the low values instead of the high ones (grooves rather than ridges).
  bool invert_height = false;
};

// A Gradient-layout representation ("normal.X/Y/Z", "albedo.R/G/B", Lambertian light basis) whose
// normals come from the field's heights by periodic central differences (NormalsFromGradients, x
// right, y up toward row 0), so the material tiles seamlessly and relights like a captured one.
Representation PatternMaterial(const GridShape& grid, const Eigen::VectorXd& field,
                               const PatternMaterialOptions& options = {});

}  // namespace photomat

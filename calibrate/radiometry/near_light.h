#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <vector>

#include "core/light_direction.h"

namespace photomat {

// A point light near the sample at a known 3-D position, with inverse-square fall-off: the
// irradiance at surface point p with normal n is intensity * max(0, n.(P - p)) / |P - p|^3.
//
// Sample frame: pixel units, origin at the image centre, x right, y up, z toward the camera; the
// sample's mean plane is z = 0, so pixel (column c, row r) of a W x H image lies at
// (c + 0.5 - W/2, H/2 - r - 0.5, 0). A lamp 1.5 image widths above the centre is at
// (0, 0, 1.5 W).
struct NearLight {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double intensity = 1.0;
};

// Where pixel (column, row) of a width x height image lies on the sample plane (plus `height`).
Eigen::Vector3d SamplePoint(int width, int height, int column, int row, double surface_height = 0);

// The distant light that stands for a near one: the direction from the sample's centre.
LightDirection NominalDirection(const NearLight& light);
std::vector<LightDirection> NominalDirections(const std::vector<NearLight>& lights);

// Reads near lights, one "x y z [intensity]" a line in the sample frame (pixel units); blank and
// '#' lines are skipped, an optional first line may hold only the count. Throws Error naming the
// file and line for malformed numbers, a light at or below the sample plane (z <= 0) or a
// non-positive intensity.
std::vector<NearLight> ReadNearLights(const std::filesystem::path& path);

}  // namespace photomat

#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/light_direction.h"

namespace photomat {

// A point light near the sample at a known 3-D position, with inverse-square fall-off: the
// irradiance at surface point p with normal n is intensity * max(0, n.(P - p)) / |P - p|^3.
//
// Sample frame: pixel units, origin at the image centre, x right, y up, z toward the camera; the
// sample's mean plane is z = 0, so pixel (column c, row r) of a W x H image lies at
// (c + 0.5 - W/2, H/2 - r - 0.5, 0). A lamp 1.5 image widths above the centre is at
// (0, 0, 1.5 W). (Read from files by calibrate/radiometry/near_light.h.)
struct NearLight {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double intensity = 1.0;
};

// Where pixel (column, row) of a width x height image lies on the sample plane (plus `height`).
Eigen::Vector3d SamplePoint(int width, int height, int column, int row, double surface_height = 0);

// The distant light that stands for a near one: the direction from the sample's centre.
LightDirection NominalDirection(const NearLight& light);
std::vector<LightDirection> NominalDirections(const std::vector<NearLight>& lights);

// A near lamp as one pixel sees it: the unit direction from the pixel's point on the sample plane
// to the lamp, and the irradiance there relative to that of a distant light from the nominal
// direction, in a capture that `calibrate apply --near-lights` has divided by the lamps' fall-off.
struct LampAtPixel {
  Eigen::Vector3d direction;
  double irradiance = 1.0;
};

// The near lamps of a calibrated capture, one per image, in the sample frame of the whole image
// (`width` x `height`), whose images were divided by the lamps' flat-field gains
// (calibrate/radiometry/flat_field.h, FlatFieldFromNearLights: intensity * l.z / d^2 / l0.z at
// the pixel, l its direction to the lamp, d the distance, l0 the nominal direction, normalised to
// a mean of 1 over all lights and pixels). A set of rows of the capture (a band of a streamed
// fit) keeps the whole frame and its `first_row`.
struct NearLighting {
  std::vector<NearLight> lamps;
  int width = 0, height = 0;
  int first_row = 0;

  // Lamp `image` seen from pixel (column, row) of this set (row counted from first_row), on the
  // sample plane (z = 0: the relief's height is unknown to a fit, as to the flat-field). A
  // surface of radiance rho(n, l) under a unit distant light shows, in the divided image,
  // rho(n, l) * (intensity / d^2) / gain = rho(n, l) * l0.z / l.z up to the gains' one
  // normalisation constant: `irradiance` is l0.z / l.z (1 at the image centre, where l = l0).
  // IMPLEMENTER CHOICE: that constant (one number for the whole capture) is left in the images'
  // brightness, as a distant-light capture's exposure is, so that a fit with near lamps and one
  // with the nominal directions read the divided images on the same scale.
  LampAtPixel At(int image, int column, int row) const;
};

}  // namespace photomat

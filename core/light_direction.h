#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

namespace photomat {

// A unit vector from the sample toward a distant light, in photomat's frame: x to the right of the
// image, y up (toward image row 0), z toward the camera. The same frame as DiLiGenT and .lp files.
//
// Slant is the angle from the camera axis (+z), tilt the angle of the projection onto the image
// plane measured from +x toward +y, both in degrees:
//   l = (cos(tilt) sin(slant), sin(tilt) sin(slant), cos(slant)).
class LightDirection {
 public:
  // Normalises (x, y, z). Throws Error for a zero-length or non-finite vector.
  static LightDirection FromVector(const Eigen::Vector3d& v);
  static LightDirection FromVector(double x, double y, double z) {
    return FromVector(Eigen::Vector3d(x, y, z));
  }
  // Throws Error unless both angles are finite.
  static LightDirection FromSlantTilt(double slant_degrees, double tilt_degrees);

  const Eigen::Vector3d& vector() const { return v_; }
  double x() const { return v_.x(); }
  double y() const { return v_.y(); }
  double z() const { return v_.z(); }

  // In [0, 180].
  double SlantDegrees() const;
  // In [0, 360); 0 for a light on the camera axis, where tilt is undefined.
  double TiltDegrees() const;

  // Angle between two directions, in degrees (numerically safe near 0 and 180).
  double AngleToDegrees(const LightDirection& other) const;

 private:
  explicit LightDirection(const Eigen::Vector3d& unit) : v_(unit) {}
  Eigen::Vector3d v_;
};

// The light grid of Dong's thesis: 12 tilts every 30 degrees (0..330) for each of the slants 30,
// 45 and 60 degrees, slant-major (36 lights).
std::vector<LightDirection> ThesisLightGrid();

// The 3 x n matrix whose columns are the light vectors (the L of photometric stereo), of all
// `lights` or of the `selected` ones, in that order.
Eigen::Matrix3Xd LightMatrix(std::span<const LightDirection> lights);
Eigen::Matrix3Xd LightMatrix(std::span<const LightDirection> lights, std::span<const int> selected);

// The `selected` lights of `lights`, in that order (a fit's lights, of the images it fits).
std::vector<LightDirection> SelectLights(std::span<const LightDirection> lights,
                                         std::span<const int> selected);

// Angle in degrees between two unit vectors, robust for nearly parallel vectors (atan2 form).
double AngleBetweenDegrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

}  // namespace photomat

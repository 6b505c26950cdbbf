#include "core/light_direction.h"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "core/error.h"

namespace photomat {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

}  // namespace

LightDirection LightDirection::FromVector(const Eigen::Vector3d& v) {
  if (!v.allFinite()) throw Error("light vector has a non-finite component");
  const double norm = v.norm();
  // Real light files hold unit vectors written with 4 to 17 digits; anything this short is a
  // placeholder or a typo, not a direction.
  if (norm < 1e-6) throw Error("zero-length light vector");
  return LightDirection(v / norm);
}

LightDirection LightDirection::FromSlantTilt(double slant_degrees, double tilt_degrees) {
  if (!std::isfinite(slant_degrees) || !std::isfinite(tilt_degrees)) {
    throw Error("slant and tilt must be finite numbers");
  }
  const double s = slant_degrees * kDegree;
  const double t = tilt_degrees * kDegree;
  return LightDirection(
      Eigen::Vector3d(std::cos(t) * std::sin(s), std::sin(t) * std::sin(s), std::cos(s)));
}

double LightDirection::SlantDegrees() const {
  return std::atan2(std::hypot(v_.x(), v_.y()), v_.z()) / kDegree;
}

double LightDirection::TiltDegrees() const {
  if (std::hypot(v_.x(), v_.y()) < 1e-12) return 0.0;
  double tilt = std::atan2(v_.y(), v_.x()) / kDegree;
  if (tilt < 0.0) tilt += 360.0;
  return tilt >= 360.0 ? 0.0 : tilt;
}

double LightDirection::AngleToDegrees(const LightDirection& other) const {
  return AngleBetweenDegrees(v_, other.v_);
}

double AngleBetweenDegrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) / kDegree;
}

Eigen::Matrix3Xd LightMatrix(std::span<const LightDirection> lights) {
  Eigen::Matrix3Xd l(3, static_cast<Eigen::Index>(lights.size()));
  for (std::size_t i = 0; i < lights.size(); ++i) {
    l.col(static_cast<Eigen::Index>(i)) = lights[i].vector();
  }
  return l;
}

Eigen::Matrix3Xd LightMatrix(std::span<const LightDirection> lights,
                             std::span<const int> selected) {
  Eigen::Matrix3Xd l(3, static_cast<Eigen::Index>(selected.size()));
  for (std::size_t i = 0; i < selected.size(); ++i) {
    l.col(static_cast<Eigen::Index>(i)) = lights[static_cast<std::size_t>(selected[i])].vector();
  }
  return l;
}

std::vector<LightDirection> SelectLights(std::span<const LightDirection> lights,
                                         std::span<const int> selected) {
  std::vector<LightDirection> out;
  out.reserve(selected.size());
  for (int i : selected) out.push_back(lights[static_cast<std::size_t>(i)]);
  return out;
}

std::vector<LightDirection> ThesisLightGrid() {
  std::vector<LightDirection> lights;
  for (double slant : {30.0, 45.0, 60.0}) {
    for (int step = 0; step < 12; ++step) {
      lights.push_back(LightDirection::FromSlantTilt(slant, 30.0 * step));
    }
  }
  return lights;
}

}  // namespace photomat

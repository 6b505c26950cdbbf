#include "core/colour.h"

#include <lcms2.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>

#include "core/text_parsing.h"

namespace photomat {

std::string_view ToString(ColourSpace space) {
  return space == ColourSpace::kSrgb ? "srgb" : "linear";
}

std::optional<ColourSpace> ParseColourSpace(std::string_view text) {
  const std::string lower = ToLower(text);
  if (lower == "linear") return ColourSpace::kLinear;
  if (lower == "srgb") return ColourSpace::kSrgb;
  return std::nullopt;
}

double SrgbToLinear(double encoded) {
  const double v = std::clamp(encoded, 0.0, 1.0);
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

double LinearToSrgb(double linear) {
  const double v = std::clamp(linear, 0.0, 1.0);
  return v <= 0.0031308 ? v * 12.92 : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

Eigen::Vector3d XyzOfChromaticity(double x, double y) { return {x / y, 1.0, (1.0 - x - y) / y}; }

std::optional<Eigen::Matrix3d> RgbToXyzMatrix(const Chromaticities& c) {
  for (int i = 1; i < 8; i += 2) {
    if (!(c[i] > 1e-6)) return std::nullopt;
  }
  Eigen::Matrix3d primaries;
  for (int k = 0; k < 3; ++k) primaries.col(k) = XyzOfChromaticity(c[2 * k], c[2 * k + 1]);
  if (std::abs(primaries.determinant()) < 1e-9) return std::nullopt;
  const Eigen::Vector3d scale = primaries.inverse() * XyzOfChromaticity(c[6], c[7]);
  return primaries * scale.asDiagonal();
}

CieLab CieLabOfLinearRec709(double r, double g, double b) {
  // Constants, computed once (thread-safe initialisation).
  static const Eigen::Matrix3d kToXyz = *RgbToXyzMatrix(kRec709Chromaticities);
  static const Eigen::Vector3d kWhite =
      XyzOfChromaticity(kRec709Chromaticities[6], kRec709Chromaticities[7]);
  const Eigen::Vector3d xyz = kToXyz * Eigen::Vector3d(r, g, b);
  const cmsCIEXYZ white = {kWhite.x(), kWhite.y(), kWhite.z()};
  const cmsCIEXYZ colour = {xyz.x(), xyz.y(), xyz.z()};
  cmsCIELab lab;
  cmsXYZ2Lab(&white, &lab, &colour);
  return {lab.L, lab.a, lab.b};
}

double CieDe2000(const CieLab& x, const CieLab& y) {
  const cmsCIELab first = {x.l, x.a, x.b};
  const cmsCIELab second = {y.l, y.a, y.b};
  return cmsCIE2000DeltaE(&first, &second, 1.0, 1.0, 1.0);
}

}  // namespace photomat

#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace photomat {

// How stored integer samples relate to light. Photometric fitting needs linear data, so sRGB
// samples are decoded with the sRGB transfer function (IEC 61966-2-1) on read.
enum class ColourSpace { kLinear, kSrgb };

std::string_view ToString(ColourSpace space);
// Accepts "linear" and "srgb" (any case); nullopt otherwise.
std::optional<ColourSpace> ParseColourSpace(std::string_view text);

// The sRGB transfer function and its inverse on [0, 1] (values outside are clamped).
double SrgbToLinear(double encoded);
double LinearToSrgb(double linear);

// Chromaticities (x, y) of the red, green and blue primaries and the white, in that order.
using Chromaticities = std::array<double, 8>;
// Rec.709 / sRGB (IEC 61966-2-1): photomat's linear RGB, white D65.
inline constexpr Chromaticities kRec709Chromaticities = {0.64, 0.33, 0.30,   0.60,
                                                         0.15, 0.06, 0.3127, 0.3290};

// The XYZ (Y = 1) of chromaticity (x, y).
Eigen::Vector3d XyzOfChromaticity(double x, double y);
// The matrix from linear RGB of these primaries to XYZ, RGB (1, 1, 1) mapping to the white's XYZ
// with Y = 1; nullopt when a y is not positive or the primaries are collinear.
std::optional<Eigen::Matrix3d> RgbToXyzMatrix(const Chromaticities& chromaticities);

// CIE 1976 L*a*b*: L* 0 (black) to 100 (the reference white).
struct CieLab {
  double l = 0.0, a = 0.0, b = 0.0;
};

// The CIELAB of linear Rec.709 RGB (1, 1, 1 = white), reference white D65, the sRGB white: XYZ by
// the primaries' matrix as IEC 61966-2-1 defines it, no chromatic adaptation (so the values are
// those of colour tools that compute sRGB's Lab under D65, e.g. scikit-image's rgb2lab; the ICC's
// D50 Lab of the same colour differs by a Bradford adaptation). Little CMS's cmsXYZ2Lab.
CieLab CieLabOfLinearRec709(double r, double g, double b);

// The CIEDE2000 colour difference (kL = kC = kH = 1), Little CMS's cmsCIE2000DeltaE: it
// reproduces Sharma, Wu and Dalal's (2005) 34 test pairs to their 4 printed decimals.
double CieDe2000(const CieLab& x, const CieLab& y);

}  // namespace photomat

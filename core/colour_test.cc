#include "core/colour.h"

#include <gtest/gtest.h>

#include <array>

namespace photomat {
namespace {

// Sharma, Wu and Dalal, "The CIEDE2000 color-difference formula: implementation notes,
// supplementary test data, and mathematical observations", Color Res. Appl. 30(1), 2005, table 1:
// L*a*b* of both colours and the published difference (4 decimals). The pairs exercise the
// formula's hue-angle discontinuities, the mean hue across 0/360 degrees and the near-neutral
// colours where a* and b* are tiny.
constexpr std::array<std::array<double, 7>, 34> kSharmaPairs = {{
    {50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425},
    {50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615},
    {50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412},
    {50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000},
    {50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000},
    {50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000},
    {50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669},
    {50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669},
    {50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792},
    {50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792},
    {50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195},
    {50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195},
    {50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045},
    {50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045},
    {50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461},
    {50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065},
    {50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492},
    {50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977},
    {50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030},
    {50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535},
    {50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000},
    {50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000},
    {50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000},
    {50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000},
    {60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644},
    {63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630},
    {61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731},
    {35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645},
    {22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373},
    {36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146},
    {90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441},
    {90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381},
    {6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377},
    {2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082},
}};

TEST(ColourTest, CieDe2000ReproducesSharmaWuDalalsTestPairs) {
  for (const auto& p : kSharmaPairs) {
    const CieLab x{p[0], p[1], p[2]}, y{p[3], p[4], p[5]};
    // The table prints 4 decimals: half a unit of the last one, plus float noise (measured: at
    // most 4.95e-5).
    EXPECT_NEAR(CieDe2000(x, y), p[6], 5.0001e-5) << p[0] << " " << p[1] << " " << p[2];
    EXPECT_DOUBLE_EQ(CieDe2000(x, y), CieDe2000(y, x));
  }
  EXPECT_EQ(CieDe2000({40.0, 10.0, -5.0}, {40.0, 10.0, -5.0}), 0.0);
}

TEST(ColourTest, CieLabOfRec709WhiteGreyAndPrimariesUnderD65) {
  const CieLab white = CieLabOfLinearRec709(1.0, 1.0, 1.0);
  EXPECT_NEAR(white.l, 100.0, 1e-9);
  EXPECT_NEAR(white.a, 0.0, 1e-9);
  EXPECT_NEAR(white.b, 0.0, 1e-9);
  const CieLab black = CieLabOfLinearRec709(0.0, 0.0, 0.0);
  EXPECT_NEAR(black.l, 0.0, 1e-9);
  // Y = 0.18: L* = 116 0.18^(1/3) - 16, neutral.
  const CieLab grey = CieLabOfLinearRec709(0.18, 0.18, 0.18);
  EXPECT_NEAR(grey.l, 116.0 * std::cbrt(0.18) - 16.0, 1e-9);
  EXPECT_NEAR(grey.a, 0.0, 1e-9);
  EXPECT_NEAR(grey.b, 0.0, 1e-9);
  // Below the cube root's linear segment, (6/29)^3: L* = (29/3)^3 Y.
  EXPECT_NEAR(CieLabOfLinearRec709(0.001, 0.001, 0.001).l, std::pow(29.0 / 3.0, 3.0) * 0.001, 1e-9);
  // sRGB's primaries under D65, as colour references print them (e.g. Lindbloom's calculator
  // with the sRGB matrix, scikit-image's rgb2lab): red (53.2408, 80.0925, 67.2032), green
  // (87.7347, -86.1827, 83.1793), blue (32.2970, 79.1875, -107.8602). Those use IEC 61966-2-1's
  // matrix rounded to 4 decimals and a rounded white; here both come from the chromaticities
  // exactly. Measured differences at most 7.8e-3 (green's b*, blue's a*); bound twice that.
  const std::array<std::array<double, 6>, 3> primaries = {{
      {1.0, 0.0, 0.0, 53.2408, 80.0925, 67.2032},
      {0.0, 1.0, 0.0, 87.7347, -86.1827, 83.1793},
      {0.0, 0.0, 1.0, 32.2970, 79.1875, -107.8602},
  }};
  for (const auto& p : primaries) {
    const CieLab lab = CieLabOfLinearRec709(p[0], p[1], p[2]);
    EXPECT_NEAR(lab.l, p[3], 0.016) << p[0] << p[1] << p[2];
    EXPECT_NEAR(lab.a, p[4], 0.016) << p[0] << p[1] << p[2];
    EXPECT_NEAR(lab.b, p[5], 0.016) << p[0] << p[1] << p[2];
  }
}

TEST(ColourTest, RgbToXyzMatrixMapsWhiteToTheWhitesXyzAndRefusesDegeneratePrimaries) {
  const Eigen::Matrix3d m = *RgbToXyzMatrix(kRec709Chromaticities);
  const Eigen::Vector3d white = m * Eigen::Vector3d::Ones();
  EXPECT_NEAR(white.y(), 1.0, 1e-12);
  EXPECT_NEAR(white.x(), 0.3127 / 0.3290, 1e-12);
  // IEC 61966-2-1's Y row: 0.2126, 0.7152, 0.0722 (4 decimals).
  EXPECT_NEAR(m(1, 0), 0.2126, 5e-5);
  EXPECT_NEAR(m(1, 1), 0.7152, 5e-5);
  EXPECT_NEAR(m(1, 2), 0.0722, 5e-5);
  Chromaticities zero_y = kRec709Chromaticities;
  zero_y[1] = 0.0;
  EXPECT_FALSE(RgbToXyzMatrix(zero_y).has_value());
  const Chromaticities collinear = {0.2, 0.2, 0.4, 0.4, 0.6, 0.6, 0.3127, 0.3290};
  EXPECT_FALSE(RgbToXyzMatrix(collinear).has_value());
}

}  // namespace
}  // namespace photomat

#include "core/near_light.h"

#include <gtest/gtest.h>

#include <cmath>

namespace photomat {
namespace {

NearLighting OneLamp(int width, int height, const Eigen::Vector3d& position) {
  NearLighting lighting;
  lighting.lamps = {NearLight{position, 2.0}};
  lighting.width = width;
  lighting.height = height;
  return lighting;
}

TEST(NearLightTest, TheCentrePixelSeesTheNominalDirectionAtUnitIrradiance) {
  // A 5 x 5 image: pixel (2, 2) lies at the frame's origin.
  const Eigen::Vector3d lamp(30.0, -20.0, 60.0);
  const LampAtPixel centre = OneLamp(5, 5, lamp).At(0, 2, 2);
  EXPECT_LT((centre.direction - lamp.normalized()).norm(), 1e-15);
  EXPECT_NEAR(centre.irradiance, 1.0, 1e-15);
}

TEST(NearLightTest, AFlatSurfaceSeesTheNominalLightEverywhere) {
  // The divided images of a flat matte surface (n = +z) are those of the nominal distant light:
  // n.l times the relative irradiance is l0.z at every pixel. At a corner the lamp's direction
  // differs from the nominal one by degrees, so the property is not trivial.
  const Eigen::Vector3d lamp(10.0, 5.0, 40.0);
  const NearLighting lighting = OneLamp(64, 48, lamp);
  const double nominal_z = lamp.normalized().z();
  for (const auto& [column, row] : {std::pair{0, 0}, {63, 0}, {0, 47}, {63, 47}, {20, 30}}) {
    const LampAtPixel at = lighting.At(0, column, row);
    const Eigen::Vector3d expected = (lamp - SamplePoint(64, 48, column, row)).normalized();
    EXPECT_LT((at.direction - expected).norm(), 1e-15);
    EXPECT_NEAR(at.direction.z() * at.irradiance, nominal_z, 1e-14);
  }
  EXPECT_GT(std::acos(lighting.At(0, 0, 47).direction.dot(lamp.normalized())), 0.5);
}

TEST(NearLightTest, ABandSeesTheLampAsTheWholeImageDoes) {
  const Eigen::Vector3d lamp(-15.0, 25.0, 50.0);
  NearLighting band = OneLamp(40, 30, lamp);
  band.first_row = 12;
  const NearLighting whole = OneLamp(40, 30, lamp);
  const LampAtPixel in_band = band.At(0, 7, 3);
  const LampAtPixel in_whole = whole.At(0, 7, 15);
  EXPECT_EQ(in_band.direction, in_whole.direction);
  EXPECT_EQ(in_band.irradiance, in_whole.irradiance);
}

}  // namespace
}  // namespace photomat

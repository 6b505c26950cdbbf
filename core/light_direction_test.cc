#include "core/light_direction.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"

namespace photomat {
namespace {

TEST(LightDirectionTest, SlantTiltFollowsTheThesisFormula) {
  const auto l = LightDirection::FromSlantTilt(60.0, 120.0);
  const double s = 60.0 * M_PI / 180.0, t = 120.0 * M_PI / 180.0;
  EXPECT_NEAR(l.x(), std::cos(t) * std::sin(s), 1e-15);
  EXPECT_NEAR(l.y(), std::sin(t) * std::sin(s), 1e-15);
  EXPECT_NEAR(l.z(), std::cos(s), 1e-15);
}

TEST(LightDirectionTest, TiltIsMeasuredFromXTowardY) {
  EXPECT_NEAR(LightDirection::FromSlantTilt(45, 90).y(), std::sin(M_PI / 4), 1e-15);
  EXPECT_NEAR(LightDirection::FromSlantTilt(45, 90).x(), 0.0, 1e-15);
  EXPECT_NEAR(LightDirection::FromSlantTilt(45, 180).x(), -std::sin(M_PI / 4), 1e-15);
}

TEST(LightDirectionTest, SlantTiltRoundTrip) {
  for (double slant : {1.0, 30.0, 45.0, 60.0, 89.0}) {
    for (double tilt : {0.0, 30.0, 179.0, 181.0, 330.0, 359.5}) {
      const auto l = LightDirection::FromSlantTilt(slant, tilt);
      EXPECT_NEAR(l.SlantDegrees(), slant, 1e-9);
      EXPECT_NEAR(l.TiltDegrees(), tilt, 1e-9);
    }
  }
}

TEST(LightDirectionTest, OverheadLightHasTiltZero) {
  const auto l = LightDirection::FromSlantTilt(0.0, 123.0);
  EXPECT_DOUBLE_EQ(l.SlantDegrees(), 0.0);
  EXPECT_DOUBLE_EQ(l.TiltDegrees(), 0.0);
}

TEST(LightDirectionTest, FromVectorNormalises) {
  const auto l = LightDirection::FromVector(3.0, 0.0, 4.0);
  EXPECT_DOUBLE_EQ(l.vector().norm(), 1.0);
  EXPECT_DOUBLE_EQ(l.x(), 0.6);
}

TEST(LightDirectionTest, RejectsZeroAndNonFiniteVectors) {
  EXPECT_THROW(LightDirection::FromVector(0, 0, 0), Error);
  EXPECT_THROW(LightDirection::FromVector(NAN, 0, 1), Error);
  EXPECT_THROW(LightDirection::FromSlantTilt(INFINITY, 0), Error);
}

TEST(LightDirectionTest, AngleIsAccurateForNearlyEqualDirections) {
  const auto a = LightDirection::FromSlantTilt(30, 0);
  const auto b = LightDirection::FromSlantTilt(30 + 1e-6, 0);
  EXPECT_NEAR(a.AngleToDegrees(b), 1e-6, 1e-12);
}

TEST(LightDirectionTest, ThesisGridIsTwelveTiltsTimesThreeSlants) {
  const auto grid = ThesisLightGrid();
  ASSERT_EQ(grid.size(), 36u);
  EXPECT_NEAR(grid[0].SlantDegrees(), 30, 1e-9);
  EXPECT_NEAR(grid[13].SlantDegrees(), 45, 1e-9);
  EXPECT_NEAR(grid[13].TiltDegrees(), 30, 1e-9);
  EXPECT_NEAR(grid[35].SlantDegrees(), 60, 1e-9);
  EXPECT_NEAR(grid[35].TiltDegrees(), 330, 1e-9);
}

// SelectLights keeps the chosen lights in the order asked, and LightMatrix of them is the
// selected columns.
TEST(LightDirectionTest, SelectLightsTakesTheChosenOnesInOrder) {
  const auto grid = ThesisLightGrid();
  const std::vector<int> chosen = {13, 2, 35};
  const std::vector<LightDirection> selected = SelectLights(grid, chosen);
  ASSERT_EQ(selected.size(), 3u);
  for (std::size_t j = 0; j < chosen.size(); ++j) {
    EXPECT_EQ(selected[j].vector(), grid[static_cast<std::size_t>(chosen[j])].vector()) << j;
  }
  EXPECT_EQ(LightMatrix(selected), LightMatrix(grid, chosen));
  EXPECT_TRUE(SelectLights(grid, {}).empty());
}

}  // namespace
}  // namespace photomat

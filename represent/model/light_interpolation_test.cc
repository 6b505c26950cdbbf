#include "represent/model/light_interpolation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "core/error.h"
#include "core/random.h"

namespace photomat {
namespace {

using Scheme = LightInterpolator::Scheme;

std::map<int, double> AsMap(const std::vector<std::pair<int, double>>& weights) {
  std::map<int, double> map;
  double total = 0.0;
  for (const auto& [node, w] : weights) {
    map[node] += w;
    total += w;
    EXPECT_GT(w, 0.0);
  }
  EXPECT_NEAR(total, 1.0, 1e-12);
  return map;
}

// Grid index of (slant 30/45/60, tilt step) in ThesisLightGrid().
int GridIndex(int slant_row, int tilt_step) { return slant_row * 12 + tilt_step % 12; }

TEST(LightInterpolatorTest, ThesisGridUsesSlantRings) {
  const LightInterpolator interpolator(ThesisLightGrid());
  EXPECT_EQ(interpolator.scheme(), Scheme::kSlantRings);
}

TEST(LightInterpolatorTest, RingsAreExactAtNodes) {
  const auto grid = ThesisLightGrid();
  const LightInterpolator interpolator(grid);
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const auto weights = AsMap(interpolator.Weights(grid[i]));
    ASSERT_EQ(weights.size(), 1u);
    EXPECT_EQ(weights.begin()->first, static_cast<int>(i));
  }
}

TEST(LightInterpolatorTest, RingsGiveTheThesisBilinearWeights) {
  // (tilt 40, slant 50): t1 = (40 - 30) / 30, t2 = (50 - 45) / 15 between tilts 30/60, slants
  // 45/60.
  const LightInterpolator interpolator(ThesisLightGrid());
  const auto w = AsMap(interpolator.Weights(LightDirection::FromSlantTilt(50, 40)));
  const double t1 = 1.0 / 3.0, t2 = 1.0 / 3.0;
  EXPECT_NEAR(w.at(GridIndex(1, 1)), (1 - t1) * (1 - t2), 1e-9);
  EXPECT_NEAR(w.at(GridIndex(1, 2)), t1 * (1 - t2), 1e-9);
  EXPECT_NEAR(w.at(GridIndex(2, 1)), (1 - t1) * t2, 1e-9);
  EXPECT_NEAR(w.at(GridIndex(2, 2)), t1 * t2, 1e-9);
}

TEST(LightInterpolatorTest, TiltWrapsAroundBetween330And0) {
  const LightInterpolator interpolator(ThesisLightGrid());
  const auto w = AsMap(interpolator.Weights(LightDirection::FromSlantTilt(45, 350)));
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NEAR(w.at(GridIndex(1, 11)), 1.0 / 3.0, 1e-9);  // tilt 330
  EXPECT_NEAR(w.at(GridIndex(1, 0)), 2.0 / 3.0, 1e-9);   // tilt 0 = 360
}

TEST(LightInterpolatorTest, LeftOutNodeIsBridgedByItsRingNeighbours) {
  auto grid = ThesisLightGrid();
  const LightDirection held_out = grid[GridIndex(1, 3)];  // slant 45, tilt 90
  grid.erase(grid.begin() + GridIndex(1, 3));
  const LightInterpolator interpolator(grid);
  EXPECT_EQ(interpolator.scheme(), Scheme::kSlantRings);
  const auto w = AsMap(interpolator.Weights(held_out));
  ASSERT_EQ(w.size(), 2u);  // tilts 60 and 120 at slant 45, half each
  for (const auto& [node, weight] : w) {
    EXPECT_NEAR(grid[node].SlantDegrees(), 45, 1e-9);
    EXPECT_NEAR(weight, 0.5, 1e-9);
  }
}

TEST(LightInterpolatorTest, SlantsOutsideTheRingsClamp) {
  const LightInterpolator interpolator(ThesisLightGrid());
  const auto low = AsMap(interpolator.Weights(LightDirection::FromSlantTilt(10, 0)));
  ASSERT_EQ(low.size(), 1u);
  EXPECT_EQ(low.begin()->first, GridIndex(0, 0));
  const auto high = AsMap(interpolator.Weights(LightDirection::FromSlantTilt(80, 60)));
  ASSERT_EQ(high.size(), 1u);
  EXPECT_EQ(high.begin()->first, GridIndex(2, 2));
}

TEST(LightInterpolatorTest, OverheadPoleJoinsRings) {
  auto lights = ThesisLightGrid();
  lights.push_back(LightDirection::FromSlantTilt(0, 0));
  const LightInterpolator interpolator(lights);
  EXPECT_EQ(interpolator.scheme(), Scheme::kSlantRings);
  const auto w = AsMap(interpolator.Weights(LightDirection::FromSlantTilt(15, 0)));
  EXPECT_NEAR(w.at(36), 0.5, 1e-9);
  EXPECT_NEAR(w.at(GridIndex(0, 0)), 0.5, 1e-9);
}

std::vector<LightDirection> IrregularLights(int count, std::uint64_t seed) {
  Random random(seed);
  std::vector<LightDirection> lights;
  for (int i = 0; i < count; ++i) {
    lights.push_back(LightDirection::FromSlantTilt(random.Uniform(5, 60), random.Uniform(0, 360)));
  }
  return lights;
}

TEST(LightInterpolatorTest, IrregularLightsAreTriangulatedAndExactAtNodes) {
  const auto lights = IrregularLights(40, 5);
  const LightInterpolator interpolator(lights);
  EXPECT_EQ(interpolator.scheme(), Scheme::kTriangulation);
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const auto w = AsMap(interpolator.Weights(lights[i]));
    EXPECT_NEAR(w.at(static_cast<int>(i)), 1.0, 1e-6);
  }
}

TEST(LightInterpolatorTest, TriangulationReproducesLinearFunctionsOfTheProjection) {
  // Barycentric interpolation is exact for functions linear in the projected coordinates.
  const auto lights = IrregularLights(40, 6);
  const LightInterpolator interpolator(lights);
  const auto f = [](const LightDirection& l) {
    const double s = l.SlantDegrees() * M_PI / 180, t = l.TiltDegrees() * M_PI / 180;
    return 2.0 + 3.0 * s * std::cos(t) - 1.5 * s * std::sin(t);
  };
  Random random(7);
  int inside = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const auto query = LightDirection::FromSlantTilt(random.Uniform(0, 55), random.Uniform(0, 360));
    const auto weights = interpolator.Weights(query);
    if (weights.size() < 3) continue;  // on the boundary: clamped, not interpolated
    double value = 0.0;
    for (const auto& [node, w] : weights) value += w * f(lights[node]);
    EXPECT_NEAR(value, f(query), 1e-5);
    ++inside;
  }
  EXPECT_GT(inside, 100);
}

TEST(LightInterpolatorTest, OutsideTheHullTakesTheNearestBoundaryPoint) {
  const std::vector<LightDirection> lights = {LightDirection::FromSlantTilt(10, 0),
                                              LightDirection::FromSlantTilt(10, 120),
                                              LightDirection::FromSlantTilt(10, 240)};
  const LightInterpolator interpolator(lights, Scheme::kTriangulation);
  // Straight out beyond node 0: all weight on node 0.
  const auto w = AsMap(interpolator.Weights(LightDirection::FromSlantTilt(40, 0)));
  EXPECT_NEAR(w.at(0), 1.0, 1e-9);
}

TEST(LightInterpolatorTest, CollinearIrregularLightsAreRejected) {
  const std::vector<LightDirection> line = {LightDirection::FromSlantTilt(10, 0),
                                            LightDirection::FromSlantTilt(20, 0),
                                            LightDirection::FromSlantTilt(30, 0)};
  EXPECT_THROW(LightInterpolator interpolator(line), Error);
}

}  // namespace
}  // namespace photomat

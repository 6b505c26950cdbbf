#include "represent/model/normal_error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace photomat {
namespace {

TEST(NormalErrorTest, StatisticsOfAKnownRotation) {
  Image truth(4, 1, 3), estimate(4, 1, 3);
  const double angles[] = {1.0, 3.0, 6.0, 12.0};
  for (int x = 0; x < 4; ++x) {
    const double a = angles[x] * M_PI / 180;
    truth.at(x, 0, 2) = 1.0f;
    estimate.at(x, 0, 0) = static_cast<float>(std::sin(a));
    estimate.at(x, 0, 2) = static_cast<float>(std::cos(a));
  }
  const NormalErrorStats stats = CompareNormals(estimate, truth, Mask(4, 1, true));
  EXPECT_NEAR(stats.mean_degrees, 5.5, 1e-4);
  EXPECT_NEAR(stats.median_degrees, 4.5, 1e-4);
  EXPECT_NEAR(stats.max_degrees, 12.0, 1e-4);
  EXPECT_DOUBLE_EQ(stats.fraction_below_5_degrees, 0.5);
  EXPECT_DOUBLE_EQ(stats.fraction_below_10_degrees, 0.75);
}

}  // namespace
}  // namespace photomat

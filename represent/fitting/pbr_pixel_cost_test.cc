#include "represent/fitting/pbr_pixel_cost.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/microfacet_brdf.h"
#include "core/random.h"

namespace photomat {
namespace {

// A pixel of 24 seeded random lights in front of it, observed as the model at `truth` plus
// offsets of up to `offset` (so that some residuals are large, in Cauchy's flat part).
PbrPixelData RandomPixel(Random& random, double offset) {
  PbrPixelData data;
  while (data.lights.size() < 24) {
    std::array<double, 3> l = {random.Normal(), random.Normal(), std::abs(random.Normal())};
    const double norm = std::sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    for (double& v : l) v /= norm;
    data.lights.push_back(l);
    data.observed.push_back(
        {random.Uniform(0.0, offset), random.Uniform(0.0, offset), random.Uniform(0.0, offset)});
  }
  return data;
}

TEST(PbrPixelCostTest, CauchyShrinkSquaresToRhoAndIsSmoothAtZero) {
  const double b = 0.01;
  for (double s : {0.0, 1e-12, 1e-9, 1e-8, 1e-4, 0.01, 1.0, 100.0}) {
    const double w = CauchyShrink(s, b);
    EXPECT_NEAR(s * w * w, b * std::log1p(s / b), 1e-15 + 1e-12 * s) << s;
    double derivative = 0.0;
    CauchyShrink(s, b, &derivative);
    const double step = std::max(1e-10, 1e-6 * s);
    const double central =
        s > step ? (CauchyShrink(s + step, b) - CauchyShrink(s - step, b)) / (2 * step)
                 : (CauchyShrink(s + step, b) - CauchyShrink(s, b)) / step;
    EXPECT_NEAR(derivative, central, 1e-6 * std::abs(central) + 1e-6) << s;
  }
  EXPECT_EQ(CauchyShrink(0.0, b), 1.0);
}

// The hand-derived Jacobians against central differences of the residuals, at 200 seeded random
// pixels: normals in front of the camera, roughness from the fit's floor 0.05, F0 in [0, 1],
// observations far off the model and near it, lights on the whole upper hemisphere (some behind
// the surface). Step 1e-7; error over the entry's scale (the larger of its magnitude and 1e-3).
// Measured largest: 6.1e-7; bound 1e-5.
TEST(PbrPixelCostTest, JacobiansMatchCentralDifferences) {
  Random random(1203);
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const PbrPixelData data = RandomPixel(random, trial % 2 ? 1.0 : 0.01);
    const PbrPixelCost cost(data, std::pow(random.Uniform(0.01, 0.3), 2));
    // base red, green, blue, roughness, F0, normal x, y, z
    std::array<double, 8> x = {random.Uniform(0, 1),     random.Uniform(0, 1),
                               random.Uniform(0, 1),     random.Uniform(0.05, 1.0),
                               random.Uniform(0.0, 1.0), random.Normal() * 0.4,
                               random.Normal() * 0.4,    1.0};
    const double norm = std::sqrt(x[5] * x[5] + x[6] * x[6] + 1.0);
    for (int k = 5; k < 8; ++k) x[k] /= norm;
    const int rows = cost.num_residuals();
    const auto evaluate = [&](const std::array<double, 8>& at, double* residuals,
                              double** jacobians) {
      const double* parameters[] = {&at[0], &at[1], &at[2], &at[3], &at[4], &at[5]};
      ASSERT_TRUE(cost.Evaluate(parameters, residuals, jacobians));
    };
    std::vector<double> residuals(rows), plus(rows), minus(rows);
    std::vector<std::vector<double>> jacobian(5, std::vector<double>(rows));
    jacobian.emplace_back(3 * rows);
    double* jacobians[6];
    for (int b = 0; b < 6; ++b) jacobians[b] = jacobian[b].data();
    evaluate(x, residuals.data(), jacobians);
    for (int theta = 0; theta < 8; ++theta) {
      constexpr double kStep = 1e-7;
      std::array<double, 8> up = x, down = x;
      up[theta] += kStep;
      down[theta] -= kStep;
      evaluate(up, plus.data(), nullptr);
      evaluate(down, minus.data(), nullptr);
      for (int row = 0; row < rows; ++row) {
        const double central = (plus[row] - minus[row]) / (2 * kStep);
        const double analytic =
            theta < 5 ? jacobian[theta][row] : jacobian[5][row * 3 + (theta - 5)];
        worst = std::max(worst, std::abs(analytic - central) / std::max(std::abs(central), 1e-3));
      }
    }
  }
  std::printf("largest Jacobian error over its scale: %.3g\n", worst);
  EXPECT_LT(worst, 1e-5);
}

}  // namespace
}  // namespace photomat

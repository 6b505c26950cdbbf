#include "represent/fitting/pbr_pixel_cost.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
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
    data.lights.push_back(MicrofacetLight(l.data()));
    // Near lamps' relative irradiance (core/near_light.h), 0.7 to 1.27, and distant lights' 1
    // (not drawn from `random`: the pixels are those the bounds below were measured on).
    const std::size_t i = data.lights.size();
    data.irradiance.push_back(i % 2 ? 1.0 : 0.7 + 0.03 * static_cast<double>(i % 20));
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

// 8 seeded random parameters: base red, green, blue, roughness from the fit's floor 0.05, F0 in
// [0, 1], a unit normal in front of the camera.
std::array<double, kPbrParameters> RandomParameters(Random& random) {
  std::array<double, kPbrParameters> x = {random.Uniform(0, 1),     random.Uniform(0, 1),
                                          random.Uniform(0, 1),     random.Uniform(0.05, 1.0),
                                          random.Uniform(0.0, 1.0), random.Normal() * 0.4,
                                          random.Normal() * 0.4,    1.0};
  const double norm = std::sqrt(x[5] * x[5] + x[6] * x[6] + 1.0);
  for (int k = 5; k < 8; ++k) x[k] /= norm;
  return x;
}

// The 3 x lights residuals of PbrLightResiduals at `x`, and their Jacobian (row-major) if given.
void PixelResiduals(const PbrPixelData& data, double b, const std::array<double, 8>& x,
                    std::vector<double>& residuals, std::vector<double>* jacobian) {
  const MicrofacetSurface surface(&x[5], x[3], x[4]);
  residuals.resize(3 * data.lights.size());
  if (jacobian) jacobian->resize(3 * kPbrParameters * data.lights.size());
  for (std::size_t i = 0; i < data.lights.size(); ++i) {
    PbrLightResiduals(surface, x.data(), data.lights[i], data.irradiance[i], data.observed[i], b,
                      &residuals[3 * i], jacobian ? &(*jacobian)[3 * kPbrParameters * i] : nullptr);
  }
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
    const double b = std::pow(random.Uniform(0.01, 0.3), 2);
    const std::array<double, 8> x = RandomParameters(random);
    std::vector<double> residuals, plus, minus, jacobian;
    PixelResiduals(data, b, x, residuals, &jacobian);
    for (int theta = 0; theta < kPbrParameters; ++theta) {
      constexpr double kStep = 1e-7;
      std::array<double, 8> up = x, down = x;
      up[theta] += kStep;
      down[theta] -= kStep;
      PixelResiduals(data, b, up, plus, nullptr);
      PixelResiduals(data, b, down, minus, nullptr);
      for (std::size_t row = 0; row < residuals.size(); ++row) {
        const double central = (plus[row] - minus[row]) / (2 * kStep);
        const double analytic = jacobian[row * kPbrParameters + theta];
        worst = std::max(worst, std::abs(analytic - central) / std::max(std::abs(central), 1e-3));
      }
    }
  }
  std::printf("largest Jacobian error over its scale: %.3g\n", worst);
  EXPECT_LT(worst, 1e-5);
}

// The block Ceres sees (9 residuals, the square root of the normal equations) against the 3 x
// lights rows it stands for, at the same 200 kinds of pixel: the same cost |r|^2 (with Jacobians
// and without), gradient J^T r and Gauss-Newton matrix J^T J, to rounding: each difference over
// the largest entry of its matrix or vector (the cost: over itself). Measured largest: cost
// 6.9e-16, normal matrix 9.3e-15; gradient 4.7e-8, at a nearly singular J^T J (condition 4.9e15),
// where a pivot under the 1e-14 floor is dropped with its share of J^T r. Bounds 1e-12, 1e-12
// and 1e-6.
TEST(PbrPixelCostTest, CompressedBlockHasTheRowsCostGradientAndNormalMatrix) {
  Random random(2026);
  double worst_cost = 0.0, worst_gradient = 0.0, worst_matrix = 0.0, worst_gradient_condition = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const PbrPixelData data = RandomPixel(random, trial % 2 ? 1.0 : 0.01);
    const double b = std::pow(random.Uniform(0.01, 0.3), 2);
    const std::array<double, 8> x = RandomParameters(random);
    std::vector<double> rows, rows_jacobian;
    PixelResiduals(data, b, x, rows, &rows_jacobian);
    const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 8, Eigen::RowMajor>> j(
        rows_jacobian.data(), static_cast<Eigen::Index>(rows.size()), 8);
    const Eigen::Map<const Eigen::VectorXd> r(rows.data(), static_cast<Eigen::Index>(rows.size()));

    const PbrPixelCost cost(data, b);
    ASSERT_EQ(cost.num_residuals(), kPbrParameters + 1);
    const double* parameters[] = {&x[0], &x[1], &x[2], &x[3], &x[4], &x[5]};
    Eigen::VectorXd residuals(kPbrParameters + 1), cost_only(kPbrParameters + 1);
    Eigen::Matrix<double, kPbrParameters + 1, 8> root;
    std::vector<std::vector<double>> blocks(5, std::vector<double>(kPbrParameters + 1));
    blocks.emplace_back(3 * (kPbrParameters + 1));
    double* jacobians[6];
    for (int k = 0; k < 6; ++k) jacobians[k] = blocks[k].data();
    ASSERT_TRUE(cost.Evaluate(parameters, residuals.data(), jacobians));
    ASSERT_TRUE(cost.Evaluate(parameters, cost_only.data(), nullptr));
    for (int row = 0; row <= kPbrParameters; ++row) {
      for (int theta = 0; theta < 8; ++theta) {
        root(row, theta) = theta < 5 ? blocks[theta][row] : blocks[5][row * 3 + theta - 5];
      }
    }
    const double squared = r.squaredNorm();
    worst_cost = std::max({worst_cost, std::abs(residuals.squaredNorm() - squared) / squared,
                           std::abs(cost_only.squaredNorm() - squared) / squared});
    const Eigen::VectorXd gradient = j.transpose() * r;
    const Eigen::MatrixXd normal = j.transpose() * j;
    const double gradient_error = (root.transpose() * residuals - gradient).cwiseAbs().maxCoeff() /
                                  gradient.cwiseAbs().maxCoeff();
    if (gradient_error > worst_gradient) {
      worst_gradient = gradient_error;
      const Eigen::VectorXd eigenvalues = normal.selfadjointView<Eigen::Lower>().eigenvalues();
      worst_gradient_condition = eigenvalues.maxCoeff() / eigenvalues.minCoeff();
    }
    worst_matrix = std::max(worst_matrix, (root.transpose() * root - normal).cwiseAbs().maxCoeff() /
                                              normal.cwiseAbs().maxCoeff());
  }
  std::printf(
      "largest relative differences: cost %.3g, gradient %.3g (condition of J^T J there %.3g), "
      "normal matrix %.3g\n",
      worst_cost, worst_gradient, worst_gradient_condition, worst_matrix);
  EXPECT_LT(worst_cost, 1e-12);
  EXPECT_LT(worst_gradient, 1e-6);
  EXPECT_LT(worst_matrix, 1e-12);
}

}  // namespace
}  // namespace photomat

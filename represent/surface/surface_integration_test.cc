#include "represent/surface/surface_integration.h"

#include <gtest/gtest.h>

#include <cmath>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"

namespace photomat {
namespace {

// RMS difference after removing the mean difference (heights are known up to a constant), over
// the range of the truth.
double RelativeRmsError(const Image& estimate, const Image& truth) {
  double mean = 0.0, low = INFINITY, high = -INFINITY;
  const auto n = static_cast<double>(truth.pixel_count());
  for (std::size_t i = 0; i < truth.pixel_count(); ++i) {
    mean += (estimate.pixel(i)[0] - truth.pixel(i)[0]) / n;
    low = std::min(low, double{truth.pixel(i)[0]});
    high = std::max(high, double{truth.pixel(i)[0]});
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < truth.pixel_count(); ++i) {
    const double d = estimate.pixel(i)[0] - truth.pixel(i)[0] - mean;
    sum += d * d / n;
  }
  return std::sqrt(sum) / (high - low);
}

TEST(SurfaceIntegrationTest, FrankotChellappaRecoversAPeriodicSurface) {
  // The smooth bumps: the 4-pixel bevels of "bricks" and the 6-pixel grooves of "grooves" are too
  // sharp for their sampled slopes to be band-limited (about 1.4 % error from aliasing there).
  for (SurfacePattern pattern : {SurfacePattern::kBumps}) {
    SyntheticMaterialOptions options;
    options.pattern = pattern;
    options.width = 96;
    options.height = 64;
    const SyntheticMaterial material = MakeSyntheticMaterial(options);
    const Image height = IntegrateFrankotChellappa(GradientsFromNormals(material.normals));
    const double error = RelativeRmsError(height, material.height);
    ::testing::Test::RecordProperty("relative_rms_error", std::to_string(error));
    EXPECT_LT(error, 0.01) << ToString(pattern);
  }
}

// A non-periodic surface: a tilted paraboloid with a ripple, analytic gradients.
Image TiltedBowl(int w, int h, Image& gradients) {
  Image height(w, h, 1);
  gradients = Image(w, h, std::vector<std::string>{"p", "q"});
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const double x = col - w / 2.0, y = (h - 1 - row) - h / 2.0;
      height.at(col, row, 0) =
          static_cast<float>(0.3 * x + 0.01 * (x * x + 0.5 * y * y) + 2.0 * std::sin(x / 5.0));
      gradients.at(col, row, 0) = static_cast<float>(0.3 + 0.02 * x + 0.4 * std::cos(x / 5.0));
      gradients.at(col, row, 1) = static_cast<float>(0.01 * y);
    }
  }
  return height;
}

TEST(SurfaceIntegrationTest, PoissonRecoversANonPeriodicSurface) {
  Image gradients;
  const Image truth = TiltedBowl(80, 60, gradients);
  EXPECT_LT(RelativeRmsError(IntegratePoisson(gradients), truth), 0.01);
  // Frankot-Chellappa assumes periodicity and fails here: the reason both exist.
  EXPECT_GT(RelativeRmsError(IntegrateFrankotChellappa(gradients), truth), 0.05);
}

TEST(SurfaceIntegrationTest, PoissonHonoursTheMask) {
  Image gradients;
  const Image truth = TiltedBowl(40, 30, gradients);
  Mask mask(40, 30, false);
  for (int y = 5; y < 25; ++y) {
    for (int x = 8; x < 30; ++x) mask.Set(x, y, true);
  }
  const Image height = IntegratePoisson(gradients, mask);
  EXPECT_EQ(height.at(0, 0, 0), 0.0f);
  // Compare inside the mask, up to a constant.
  double offset = height.at(10, 10, 0) - truth.at(10, 10, 0);
  double worst = 0.0;
  for (int y = 5; y < 25; ++y) {
    for (int x = 8; x < 30; ++x) {
      worst = std::max(worst, std::abs(height.at(x, y, 0) - truth.at(x, y, 0) - offset));
    }
  }
  EXPECT_LT(worst, 0.1);
  EXPECT_THROW(IntegratePoisson(gradients, Mask(40, 30, false)), Error);
}

TEST(SurfaceIntegrationTest, ProjectionRemovesTheNonIntegrablePart) {
  SyntheticMaterialOptions options;
  options.pattern = SurfacePattern::kBumps;
  options.width = options.height = 64;
  const SyntheticMaterial material = MakeSyntheticMaterial(options);
  const Image integrable = GradientsFromNormals(material.normals);
  // Add a curl field (p, q) = (-dy psi, dx psi), which integrates to nothing.
  Image noisy = integrable;
  for (int row = 0; row < 64; ++row) {
    for (int col = 0; col < 64; ++col) {
      const double a = 2 * M_PI * col / 64, b = 2 * M_PI * (63 - row) / 64;
      noisy.at(col, row, 0) += static_cast<float>(0.2 * std::cos(b) * std::sin(a));
      noisy.at(col, row, 1) += static_cast<float>(-0.2 * std::sin(b) * std::cos(a));
    }
  }
  const Image projected = ProjectToIntegrable(noisy);
  double before = 0.0, after = 0.0;
  for (std::size_t i = 0; i < integrable.pixel_count(); ++i) {
    for (int c = 0; c < 2; ++c) {
      before += std::pow(noisy.pixel(i)[c] - integrable.pixel(i)[c], 2);
      after += std::pow(projected.pixel(i)[c] - integrable.pixel(i)[c], 2);
    }
  }
  EXPECT_LT(after, 0.01 * before);
}

TEST(SurfaceIntegrationTest, NormalsAndGradientsRoundTrip) {
  Image normals(1, 1, 3);
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, 0.9).normalized();
  for (int c = 0; c < 3; ++c) normals.values()[c] = static_cast<float>(n[c]);
  const Image back = NormalsFromGradients(GradientsFromNormals(normals));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(back.values()[c], n[c], 1e-6);
}

}  // namespace
}  // namespace photomat

#include "represent/surface/surface_integration.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

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

// A masked field (a disc with a hole and a separate island) whose gradients are not integrable.
Mask RingAndIsland(int w, int h) {
  Mask mask(w, h, false);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double r = std::hypot(x - 0.4 * w, y - 0.5 * h);
      mask.Set(x, y, (r < 0.35 * h && r > 0.1 * h) || (x > 0.85 * w && y > 0.2 * h && y < 0.4 * h));
    }
  }
  return mask;
}

TEST(SurfaceIntegrationTest, DirectAndIterativeSolversAgreeAndTheSystemIsReused) {
  Image bowl;
  TiltedBowl(90, 70, bowl);
  Image curl = bowl;
  for (int y = 0; y < 70; ++y) {
    for (int x = 0; x < 90; ++x) curl.at(x, y, 0) += static_cast<float>(0.3 * std::sin(y / 4.0));
  }
  const Mask mask = RingAndIsland(90, 70);
  const PoissonIntegrator direct(mask, PoissonSolver::kDirect);
  const PoissonIntegrator iterative(mask, PoissonSolver::kConjugateGradients);
  ASSERT_TRUE(direct.direct());
  ASSERT_FALSE(iterative.direct());
  EXPECT_TRUE(PoissonIntegrator(mask).direct());  // small: kAuto factorises
  for (const Image* gradients : {&bowl, &curl}) {
    const Image a = direct.Integrate(*gradients);
    const Image b = iterative.Integrate(*gradients);
    // Each connected piece's level is free (the Tikhonov term's choice, which the iterative
    // solve reaches less exactly), so the two agree up to a constant per piece: the ring and the
    // island (x > 0.85 w).
    double range = 0.0, worst = 0.0;
    for (const bool island : {false, true}) {
      std::vector<double> difference;
      for (int y = 0; y < 70; ++y) {
        for (int x = 0; x < 90; ++x) {
          if (mask(x, y) && (x > 0.85 * 90) == island) {
            difference.push_back(a.at(x, y, 0) - b.at(x, y, 0));
            range = std::max(range, static_cast<double>(std::abs(a.at(x, y, 0))));
          } else if (!mask(x, y)) {
            ASSERT_EQ(a.at(x, y, 0), 0.0f);
          }
        }
      }
      double mean = 0.0;
      for (double d : difference) mean += d / static_cast<double>(difference.size());
      for (double d : difference) worst = std::max(worst, std::abs(d - mean));
    }
    fmt::print("direct against conjugate gradients: {:.3g} of the range\n", worst / range);
    // Measured 8e-8 and 5e-8 of the range (float output, the iterative tolerance); bound 1e-6.
    EXPECT_LT(worst, 1e-6 * range);
    // The factorised system serves a second field as a fresh one would: the same bits.
    const Image fresh = PoissonIntegrator(mask, PoissonSolver::kDirect).Integrate(*gradients);
    const Image again = direct.Integrate(*gradients);
    EXPECT_TRUE(std::equal(fresh.values().begin(), fresh.values().end(), again.values().begin()));
  }
  EXPECT_THROW(direct.Integrate(Image(80, 70, 2)), Error);
  // A NaN inside the mask is refused (it would spread over its piece); outside it is ignored.
  Image poisoned = bowl;
  poisoned.at(0, 0, 0) = std::nanf("");
  ASSERT_FALSE(mask(0, 0));
  EXPECT_NO_THROW(direct.Integrate(poisoned));
  poisoned.at(36, 35 - 14, 1) = std::nanf("");
  ASSERT_TRUE(mask(36, 35 - 14));
  EXPECT_THROW(direct.Integrate(poisoned), Error);
  EXPECT_THROW(iterative.Integrate(poisoned), Error);
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

#include "capture/synthetic/synthetic_capture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "capture/io/load_photometric_set.h"
#include "core/error.h"
#include "core/microfacet_brdf.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

SyntheticMaterial Material(SurfacePattern pattern, double slope = 25.0) {
  SyntheticMaterialOptions options;
  options.pattern = pattern;
  options.width = 64;
  options.height = 48;
  options.max_slope_degrees = slope;
  options.seed = 3;
  return MakeSyntheticMaterial(options);
}

class SyntheticPatternTest : public ::testing::TestWithParam<SurfacePattern> {};

TEST_P(SyntheticPatternTest, NormalsAreUnitAndNoSteeperThanAsked) {
  const SyntheticMaterial m = Material(GetParam(), 25.0);
  double steepest = 0.0;
  for (std::size_t p = 0; p < m.normals.pixel_count(); ++p) {
    const auto n = m.normals.pixel(p);
    EXPECT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0, 1e-6);
    steepest = std::max(steepest, std::acos(std::min(1.0f, n[2])) * 180 / M_PI);
  }
  EXPECT_NEAR(steepest, 25.0, 1e-3);  // the steepest slope is exactly the one asked for
}

TEST_P(SyntheticPatternTest, NormalsMatchTheHeightField) {
  // Central differences of the sampled height approximate the true slope where it is smooth.
  const SyntheticMaterial m = Material(GetParam());
  const Image& h = m.height;
  double error = 0.0;
  int count = 0;
  for (int y = 1; y + 1 < h.height(); ++y) {
    for (int x = 1; x + 1 < h.width(); ++x) {
      const double p = (h.at(x + 1, y, 0) - h.at(x - 1, y, 0)) / 2.0;
      const double q = (h.at(x, y - 1, 0) - h.at(x, y + 1, 0)) / 2.0;  // y up: row - 1 is +y
      const auto n = m.normals.pixel(x, y);
      error += std::abs(-n[0] / n[2] - p) + std::abs(-n[1] / n[2] - q);
      ++count;
    }
  }
  EXPECT_LT(error / count, 0.05);  // mean slope error, against slopes up to tan(25) = 0.47
}

TEST_P(SyntheticPatternTest, SameSeedSameMaterial) {
  const SyntheticMaterial a = Material(GetParam()), b = Material(GetParam());
  EXPECT_TRUE(
      std::equal(a.height.values().begin(), a.height.values().end(), b.height.values().begin()));
  EXPECT_TRUE(
      std::equal(a.albedo.values().begin(), a.albedo.values().end(), b.albedo.values().begin()));
}

INSTANTIATE_TEST_SUITE_P(Patterns, SyntheticPatternTest,
                         ::testing::Values(SurfacePattern::kBumps, SurfacePattern::kGrooves,
                                           SurfacePattern::kBricks),
                         [](const auto& param_info) {
                           return std::string(ToString(param_info.param));
                         });

TEST(SyntheticCaptureTest, LambertianImagesAreAlbedoTimesCosine) {
  const SyntheticMaterial m = Material(SurfacePattern::kBricks);
  const auto lights = ThesisLightGrid();
  const PhotometricSet set = RenderSyntheticCapture(m, lights);
  ASSERT_EQ(set.size(), 36);
  for (int i : {0, 17, 35}) {
    for (int y : {0, 20, 47}) {
      for (int x : {0, 31, 63}) {
        const auto n = m.normals.pixel(x, y);
        const double cosine = n[0] * lights[i].x() + n[1] * lights[i].y() + n[2] * lights[i].z();
        EXPECT_GT(cosine, 0.0);  // default relief: no attached shadow on the thesis grid
        for (int c = 0; c < 3; ++c) {
          EXPECT_NEAR(set.image(i).at(x, y, c), m.albedo.at(x, y, c) * cosine, 1e-6);
        }
      }
    }
  }
}

TEST(SyntheticCaptureTest, SteepReliefCastsShadowsOnlyWhenAsked) {
  const SyntheticMaterial m = Material(SurfacePattern::kBricks, 60.0);
  const std::vector<LightDirection> low = {LightDirection::FromSlantTilt(75, 0)};
  SyntheticRenderOptions shadows;
  shadows.shadows = true;
  const PhotometricSet with = RenderSyntheticCapture(m, low, shadows);
  const PhotometricSet without = RenderSyntheticCapture(m, low);
  int cast = 0, negative = 0;
  for (std::size_t p = 0; p < m.normals.pixel_count(); ++p) {
    const auto n = m.normals.pixel(p);
    const double cosine = n[0] * low[0].x() + n[2] * low[0].z();
    EXPECT_GE(with.image(0).pixel(p)[0], 0.0f);
    if (cosine > 0.05 && with.image(0).pixel(p)[0] == 0.0f) ++cast;  // lit side, yet dark
    if (without.image(0).pixel(p)[0] < 0.0f) ++negative;
  }
  EXPECT_GT(cast, 20);
  EXPECT_GT(negative, 0);  // the linear model keeps the sign
}

TEST(SyntheticCaptureTest, SpecularAddsWhiteHighlightsAndNoiseIsSeeded) {
  const SyntheticMaterial m = Material(SurfacePattern::kBumps);
  const std::vector<LightDirection> overhead = {LightDirection::FromSlantTilt(0, 0)};
  SyntheticRenderOptions shiny;
  shiny.specular = 0.5;
  const PhotometricSet lambert = RenderSyntheticCapture(m, overhead);
  const PhotometricSet glossy = RenderSyntheticCapture(m, overhead, shiny);
  // A flat pixel facing the camera under an overhead light gets the full highlight k_s.
  double largest = 0.0;
  for (std::size_t p = 0; p < m.normals.pixel_count(); ++p) {
    const double added = glossy.image(0).pixel(p)[1] - lambert.image(0).pixel(p)[1];
    EXPECT_NEAR(added, glossy.image(0).pixel(p)[0] - lambert.image(0).pixel(p)[0], 1e-6);
    largest = std::max(largest, added);
  }
  EXPECT_NEAR(largest, 0.5, 0.01);

  SyntheticRenderOptions noisy;
  noisy.noise_sigma = 0.01;
  noisy.noise_seed = 9;
  const PhotometricSet a = RenderSyntheticCapture(m, overhead, noisy);
  const PhotometricSet b = RenderSyntheticCapture(m, overhead, noisy);
  double sum_sq = 0.0;
  for (std::size_t v = 0; v < a.image(0).values().size(); ++v) {
    ASSERT_EQ(a.image(0).values()[v], b.image(0).values()[v]);
    const double d = a.image(0).values()[v] - lambert.image(0).values()[v];
    sum_sq += d * d;
  }
  EXPECT_NEAR(std::sqrt(sum_sq / a.image(0).values().size()), 0.01, 0.001);
}

TEST(SyntheticCaptureTest, GgxImagesAreTheMicrofacetBrdfOfTheMaterialMaps) {
  const SyntheticMaterial m = Material(SurfacePattern::kBumps);
  double lowest = 1.0, highest = 0.0;
  for (float r : m.roughness.values()) {
    lowest = std::min<double>(lowest, r);
    highest = std::max<double>(highest, r);
  }
  EXPECT_GE(lowest, 0.35);
  EXPECT_LE(highest, 0.65);
  EXPECT_GT(highest - lowest, 0.1);  // a map, not a constant
  const std::vector<LightDirection> lights = {LightDirection::FromSlantTilt(0, 0),
                                              LightDirection::FromSlantTilt(40, 120)};
  SyntheticRenderOptions ggx;
  ggx.microfacet = true;
  const PhotometricSet set = RenderSyntheticCapture(m, lights, ggx);
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector3d l = lights[i].vector();
    for (std::size_t p : {std::size_t{0}, std::size_t{777}, std::size_t{2000}}) {
      const Eigen::Vector3d n(m.normals.pixel(p)[0], m.normals.pixel(p)[1], m.normals.pixel(p)[2]);
      const MicrofacetResponse<double> r =
          MicrofacetRadiance<double>(n.data(), l.data(), m.roughness.pixel(p)[0], m.f0.pixel(p)[0]);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(set.image(i).pixel(p)[c], r.diffuse * m.albedo.pixel(p)[c] + r.specular, 1e-6);
      }
    }
  }
  // F0 = 0 leaves Schlick's (1 - v.h)^5 alone (4e-5 at slant 60, the grid's lowest), which the
  // GGX peak multiplies where a normal faces the half vector.
  SyntheticMaterialOptions matte;
  matte.width = 32;
  matte.height = 32;
  matte.f0_min = matte.f0_max = 0.0;
  const SyntheticMaterial d = MakeSyntheticMaterial(matte);
  const PhotometricSet lambert = RenderSyntheticCapture(d, ThesisLightGrid());
  const PhotometricSet diffuse_ggx = RenderSyntheticCapture(d, ThesisLightGrid(), ggx);
  double worst = 0.0;
  for (int i = 0; i < lambert.size(); ++i) {
    for (std::size_t v = 0; v < lambert.image(i).values().size(); ++v) {
      worst = std::max<double>(
          worst, std::abs(diffuse_ggx.image(i).values()[v] - lambert.image(i).values()[v]));
    }
  }
  std::printf("GGX with F0 = 0 against Lambertian: largest difference %.3g\n", worst);
  EXPECT_LT(worst, 2.4e-4);  // measured 1.59e-4, bound = 1.5 x measured
  SyntheticRenderOptions both = ggx;
  both.specular = 0.5;
  EXPECT_THROW(RenderSyntheticCapture(m, lights, both), Error);
}

TEST(SyntheticCaptureTest, WrittenCaptureLoadsWithTruth) {
  testing::TempDir dir;
  const SyntheticMaterial m = Material(SurfacePattern::kGrooves);
  const PhotometricSet set = RenderSyntheticCapture(m, ThesisLightGrid());
  WriteSyntheticCapture(dir.path(), m, set);
  const LoadedSet loaded = LoadPhotometricSet(dir.path());
  EXPECT_EQ(loaded.set.size(), 36);
  ASSERT_TRUE(loaded.ground_truth_normals);
  EXPECT_TRUE(std::filesystem::exists(*loaded.ground_truth_normals));
  // 16-bit quantisation only.
  EXPECT_NEAR(loaded.set.image(5).at(10, 10, 1), set.image(5).at(10, 10, 1), 1.0 / 65535);
}

TEST(SyntheticCaptureTest, RejectsBadOptions) {
  SyntheticMaterialOptions options;
  options.width = 2;
  EXPECT_THROW(MakeSyntheticMaterial(options), Error);
  options.width = 64;
  options.max_slope_degrees = 90;
  EXPECT_THROW(MakeSyntheticMaterial(options), Error);
  options.max_slope_degrees = 25;
  options.roughness_max = 1.5;
  EXPECT_THROW(MakeSyntheticMaterial(options), Error);
  options.roughness_max = 0.5;
  options.f0_min = 0.2;
  options.f0_max = 0.1;
  EXPECT_THROW(MakeSyntheticMaterial(options), Error);
}

}  // namespace
}  // namespace photomat

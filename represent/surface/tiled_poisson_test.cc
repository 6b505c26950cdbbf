#include "represent/surface/tiled_poisson.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "represent/surface/surface_integration.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// RMS of tiled - reference over the mask, after removing the mean difference (heights are known
// up to a constant), over the reference's range on the mask.
double RelativeRmsDifference(const Image& tiled, const Image& reference, const Mask& mask) {
  double mean = 0.0, count = 0.0, low = INFINITY, high = -INFINITY;
  for (std::size_t p = 0; p < reference.pixel_count(); ++p) {
    if (mask.pixel_count() != 0 && !mask[p]) continue;
    mean += tiled.pixel(p)[0] - reference.pixel(p)[0];
    count += 1.0;
    low = std::min(low, double{reference.pixel(p)[0]});
    high = std::max(high, double{reference.pixel(p)[0]});
  }
  mean /= count;
  double sum = 0.0;
  for (std::size_t p = 0; p < reference.pixel_count(); ++p) {
    if (mask.pixel_count() != 0 && !mask[p]) continue;
    const double d = tiled.pixel(p)[0] - reference.pixel(p)[0] - mean;
    sum += d * d;
  }
  return std::sqrt(sum / count) / (high - low);
}

Image BrickGradients(int width, int height) {
  SyntheticMaterialOptions options;
  options.pattern = SurfacePattern::kBricks;
  options.width = width;
  options.height = height;
  return GradientsFromNormals(MakeSyntheticMaterial(options).normals);
}

// The bricks (sharp bevels, grooves: not smooth where tiles meet) over a size that is no multiple
// of the tile, tiles of 96 + 12 and 4 x 4 blocks, scaled down from the defaults (256 + 32, 8 x 8)
// to keep the test fast with several tiles each way.
TEST(TiledPoissonTest, BricksMatchTheInMemoryPoissonSolve) {
  const Image gradients = BrickGradients(250, 210);
  TiledPoissonOptions options;
  options.tile = 96;
  options.overlap = 12;
  options.coarse_factor = 4;
  const Image tiled = IntegrateTiledPoisson(gradients, Mask(), options);
  const Image whole = IntegratePoisson(gradients);
  const double difference = RelativeRmsDifference(tiled, whole, Mask());
  ::testing::Test::RecordProperty("relative_rms_difference", std::to_string(difference));
  std::printf("tiled Poisson on bricks 250 x 210: relative RMS difference %.3g\n", difference);
  // Measured: 4.36e-3 (300 x 260 with tiles of 128 + 16: 2.05e-3; the error falls as the
  // overlap grows); bound 1.4 x.
  EXPECT_LT(difference, 6e-3);
}

// A disc with a hole and an island: pieces of the mask that are one region in the image but
// several within a tile each get their own level from the coarse grid.
TEST(TiledPoissonTest, MaskedPiecesKeepTheirLevels) {
  const int width = 200, height = 180;
  const Image gradients = BrickGradients(width, height);
  Mask mask(width, height, false);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double r = std::hypot(x - 90.0, y - 90.0);
      const bool island = x >= 182 && x < 196 && y >= 20 && y < 160;
      mask.Set(x, y, (r < 85.0 && r > 20.0) || island);
    }
  }
  TiledPoissonOptions options;
  options.tile = 64;
  options.overlap = 8;
  options.coarse_factor = 4;
  const Image tiled = IntegrateTiledPoisson(gradients, mask, options);
  const Image whole = IntegratePoisson(gradients, mask);
  // Only the disc: the island is a separate region, whose level no integration fixes.
  Mask disc = mask;
  for (int y = 0; y < height; ++y) {
    for (int x = 182; x < 196; ++x) disc.Set(x, y, false);
  }
  const double difference = RelativeRmsDifference(tiled, whole, disc);
  std::printf("tiled Poisson on a masked disc: relative RMS difference %.3g\n", difference);
  // Measured: 1.06e-2 (the blocks the mask's edge cuts average fewer pixels, and the hole's and
  // the disc's edges are where tiles' Neumann boundaries cut the ring); bound 1.4 x.
  EXPECT_LT(difference, 1.5e-2);
  for (std::size_t p = 0; p < tiled.pixel_count(); ++p) {
    if (!mask[p]) {
      ASSERT_EQ(tiled.pixel(p)[0], 0.0f);
    }
  }
}

// In-memory exports: the exact solve up to kDirectPoissonUnknowns masked pixels (the same bits as
// IntegratePoisson), the tiled one above it with its mean over the mask removed.
TEST(TiledPoissonTest, AnySizeIsExactWhenSmallAndTiledWhenLarge) {
  const Image small = BrickGradients(64, 48);
  Mask disc(64, 48, false);
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) disc.Set(x, y, std::hypot(x - 30, y - 24) < 20);
  }
  for (const Mask& mask : {Mask(), disc}) {
    const Image exact = IntegratePoisson(small, mask);
    const Image any = IntegratePoissonAnySize(small, mask);
    EXPECT_TRUE(std::equal(any.values().begin(), any.values().end(), exact.values().begin()));
  }
  // 520 x 510 = 265,200 pixels, above 2^18.
  const Image large = BrickGradients(520, 510);
  const Image any = IntegratePoissonAnySize(large, Mask());
  const Image tiled = IntegrateTiledPoisson(large, Mask());
  double mean = 0.0, tiled_mean = 0.0;
  for (std::size_t p = 0; p < any.pixel_count(); ++p) {
    mean += any.pixel(p)[0];
    tiled_mean += tiled.pixel(p)[0];
  }
  mean /= static_cast<double>(any.pixel_count());
  tiled_mean /= static_cast<double>(any.pixel_count());
  EXPECT_NEAR(mean, 0.0, 1e-4);
  for (std::size_t p = 0; p < any.pixel_count(); ++p) {
    ASSERT_EQ(any.pixel(p)[0], static_cast<float>(tiled.pixel(p)[0] - tiled_mean)) << p;
  }
}

TEST(TiledPoissonTest, CoarseGridStaysSmall) {
  TiledPoissonOptions options;
  EXPECT_EQ(CoarseFactor(1000, 1000, options), 8);
  // 50 megapixels: 8 x 8 blocks would be 786 k, within the 2^20 bound.
  EXPECT_EQ(CoarseFactor(8688, 5792, options), 8);
  EXPECT_EQ(CoarseFactor(20000, 20000, options), 32);
}

TEST(TiledPoissonTest, BadTilingAndEmptyMaskAreErrors) {
  const Image gradients = BrickGradients(40, 40);
  TiledPoissonOptions options;
  options.tile = 16;
  options.overlap = 12;
  EXPECT_THAT([&] { IntegrateTiledPoisson(gradients, Mask(), options); },
              ThrowsMessage<Error>(HasSubstr("tiles of at least twice it")));
  EXPECT_THAT([&] { IntegrateTiledPoisson(gradients, Mask(40, 40, false)); },
              ThrowsMessage<Error>(HasSubstr("the mask selects no pixel")));
}

}  // namespace
}  // namespace photomat

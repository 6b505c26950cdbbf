#include "relight/render/relight.h"

#include <gtest/gtest.h>

#include "capture/io/load_photometric_set.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/fit.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

TEST(RelightTest, SweepCirclesAtOneSlant) {
  const auto sweep = LightSweep(8, 60);
  ASSERT_EQ(sweep.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(sweep[i].SlantDegrees(), 60, 1e-9);
    EXPECT_NEAR(sweep[i].TiltDegrees(), 45.0 * i, 1e-9);
  }
  EXPECT_THROW(LightSweep(0, 60), Error);
  EXPECT_THROW(LightSweep(4, 95), Error);
}

TEST(RelightTest, RelitSetReloadsAsAPhotometricSetWithItsLights) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 32);
  const Representation gradient = Fit(synthetic.set, Method::Parse("gradient"));
  const auto lights = LightSweep(6, 45);
  RelitOutputOptions options;
  options.format = RelitFormat::kPng16;
  WriteRelitSet(dir.path(), gradient, lights, options);
  const LoadedSet loaded = LoadPhotometricSet(dir.path());
  ASSERT_EQ(loaded.set.size(), 6);
  for (int i = 0; i < 6; ++i) {
    EXPECT_LT(loaded.set.light(i).AngleToDegrees(lights[i]), 1e-9);
    const Image expected = gradient.Relight(lights[i]);
    for (std::size_t v = 0; v < expected.values().size(); v += 11) {
      EXPECT_NEAR(loaded.set.image(i).values()[v], std::clamp(expected.values()[v], 0.0f, 1.0f),
                  1.0 / 65535);
    }
  }
}

TEST(RelightTest, EightBitOutputIsSrgbAndReadsBackLinear) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 16);
  const Representation ptm = Fit(synthetic.set, Method::Parse("ptm"));
  const auto light = LightDirection::FromSlantTilt(30, 45);
  WriteRelitImage(dir / "x.png", ptm, light);
  const LoadedImage loaded = ReadImage(dir / "x.png");
  EXPECT_EQ(loaded.info.bits_per_sample, 8);
  const Image expected = ptm.Relight(light);
  // sRGB 8-bit steps are at most 0.0056 linear for values up to 1.
  for (std::size_t v = 0; v < expected.values().size(); ++v) {
    EXPECT_NEAR(loaded.image.values()[v], std::clamp(expected.values()[v], 0.0f, 1.0f), 0.006);
  }
}

}  // namespace
}  // namespace photomat

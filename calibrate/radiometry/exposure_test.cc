#include "calibrate/radiometry/exposure.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

PhotometricSet TwoImages() {
  Image a(4, 2, 3), b(4, 2, 3);
  for (float& v : a.values()) v = 0.5f;
  for (float& v : b.values()) v = 0.25f;
  a.at(1, 0, 2) = 1.0f;                              // clipped blue
  for (int c = 0; c < 3; ++c) b.at(3, 1, c) = 0.0f;  // no signal
  return PhotometricSet(
      {a, b}, {LightDirection::FromVector(0, 0, 1), LightDirection::FromSlantTilt(30, 0)});
}

TEST(ExposureTest, MasksClippedAndUnderExposedPixels) {
  const auto masks = MeasuredPixelMasks(TwoImages());
  ASSERT_EQ(masks.size(), 2u);
  EXPECT_FALSE(masks[0](1, 0));
  EXPECT_TRUE(masks[0](3, 1));
  EXPECT_FALSE(masks[1](3, 1));
  EXPECT_EQ(masks[0].CountSet(), 7u);
  EXPECT_EQ(masks[1].CountSet(), 7u);
  ExposureLimits strict;
  strict.under_exposure = 0.3;  // image b is all below it
  EXPECT_EQ(MeasuredPixelMasks(TwoImages(), strict)[1].CountSet(), 0u);
  const ExposureCounts counts = CountExposureFaults(TwoImages());
  EXPECT_EQ(counts.clipped, (std::vector<std::size_t>{1, 0}));
  EXPECT_EQ(counts.under_exposed, (std::vector<std::size_t>{0, 1}));
}

TEST(ExposureTest, DarkFrameIsTheMeanOfItsFramesAndIsSubtracted) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "dark");
  Image one(4, 2, 3), two(4, 2, 3);
  for (float& v : one.values()) v = 0.02f;
  for (float& v : two.values()) v = 0.04f;
  WriteImage(dir / "dark" / "d1.exr", one);
  WriteImage(dir / "dark" / "d2.exr", two);
  const Image dark = ReadDarkFrame(dir / "dark");
  EXPECT_FLOAT_EQ(dark.at(2, 1, 0), 0.03f);
  const PhotometricSet corrected = SubtractDarkFrame(TwoImages(), dark);
  EXPECT_FLOAT_EQ(corrected.image(0).at(0, 0, 0), 0.47f);
  EXPECT_FLOAT_EQ(corrected.image(1).at(3, 1, 0), -0.03f);  // kept negative: no bias
  EXPECT_THROW(SubtractDarkFrame(TwoImages(), Image(3, 2, 3)), Error);
  std::filesystem::create_directories(dir / "empty");
  EXPECT_THROW(ReadDarkFrame(dir / "empty"), Error);
  WriteImage(dir / "dark" / "d3.exr", Image(5, 2, 3));
  EXPECT_THROW(ReadDarkFrame(dir / "dark"), Error);
}

}  // namespace
}  // namespace photomat

#include "relight/render/display_image.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

TEST(DisplayImageTest, EveryCodeIsStoredAsItIsAndTaggedSrgb) {
  testing::TempDir dir;
  Image codes(256, 1, 3);
  for (int k = 0; k < 256; ++k) {
    for (int c = 0; c < 3; ++c)
      codes.at(k, 0, c) = static_cast<float>(((k + 85 * c) % 256) / 255.0);
  }
  WriteDisplayCodes(dir / "codes.png", codes);
  ImageReadOptions raw;
  raw.colour_space = ColourSpace::kLinear;  // codes / 255, no transfer curve
  const LoadedImage loaded = ReadImage(dir / "codes.png", raw);
  EXPECT_EQ(loaded.info.bits_per_sample, 8);
  for (int k = 0; k < 256; ++k) {
    for (int c = 0; c < 3; ++c) ASSERT_EQ(loaded.image.at(k, 0, c), codes.at(k, 0, c)) << k;
  }
  // Read as the file says: its PNG sRGB chunk decides (not the 8-bit default), and wins over a
  // value given for untagged images, so the codes decode through the sRGB curve.
  ImageReadOptions untagged_linear;
  untagged_linear.untagged_colour_space = ColourSpace::kLinear;
  const LoadedImage tagged = ReadImage(dir / "codes.png", untagged_linear);
  EXPECT_EQ(tagged.info.encoding.decided_by, "png-srgb");
  EXPECT_EQ(tagged.info.colour_space, ColourSpace::kSrgb);
  for (int k = 0; k < 256; ++k) {
    for (int c = 0; c < 3; ++c) {
      const double code = codes.at(k, 0, c);
      const double srgb =
          code <= 0.04045 ? code / 12.92 : std::pow((code + 0.055) / 1.055, 2.4);  // IEC 61966-2-1
      // Measured 3.0e-8 (float rounding); bound 1e-6. Ignoring the tag would be 0.5 off.
      ASSERT_NEAR(tagged.image.at(k, 0, c), srgb, 1e-6) << k;
    }
  }
}

// The tag is read, not assumed from the bit depth: the same codes in an 8-bit PNG tagged linear
// (gAMA 1.0, what WriteImage writes for linear integer data) read back as the codes themselves.
TEST(DisplayImageTest, AnEightBitPngTaggedLinearReadsLinear) {
  testing::TempDir dir;
  Image codes(256, 1, 1);
  for (int k = 0; k < 256; ++k) codes.at(k, 0, 0) = static_cast<float>(k / 255.0);
  ImageWriteOptions linear;
  linear.sample_type = SampleType::kUint8;
  linear.encoding = ColourSpace::kLinear;
  WriteImage(dir / "linear.png", codes, linear);
  const LoadedImage loaded = ReadImage(dir / "linear.png");
  EXPECT_EQ(loaded.info.encoding.decided_by, "png-gama");
  EXPECT_EQ(loaded.info.colour_space, ColourSpace::kLinear);
  // Measured 3.0e-8; bound 1e-6. Decoded as sRGB, code 128 would read 0.216 instead of 0.502.
  for (int k = 0; k < 256; ++k) ASSERT_NEAR(loaded.image.at(k, 0, 0), k / 255.0, 1e-6) << k;
}

}  // namespace
}  // namespace photomat

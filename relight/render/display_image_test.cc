#include "relight/render/display_image.h"

#include <gtest/gtest.h>

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
  // Read as the file says (sRGB), the codes decode through the sRGB curve.
  EXPECT_EQ(ReadImage(dir / "codes.png").info.colour_space, ColourSpace::kSrgb);
}

}  // namespace
}  // namespace photomat

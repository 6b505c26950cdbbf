#include "capture/live/pixel_format.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "capture/live/testing/frame_encoding.h"
#include "core/error.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;

float Srgb(int code) { return static_cast<float>(SrgbToLinear(code / 255.0)); }

TEST(PixelFormatTest, NamesAndFourccsRoundTrip) {
  for (PixelFormat format : AllPixelFormats()) {
    EXPECT_EQ(ParsePixelFormat(ToString(format)), format);
    EXPECT_EQ(PixelFormatFromV4l2(V4l2FourCc(format)), format);
  }
  EXPECT_EQ(ParsePixelFormat("mjpeg"), PixelFormat::kMjpeg);
  EXPECT_EQ(ParsePixelFormat("rgb24"), PixelFormat::kRgb24);
  EXPECT_EQ(ParsePixelFormat("NV12"), std::nullopt);
  EXPECT_EQ(FourCcToString(V4l2FourCc(PixelFormat::kY16)), "Y16");
  EXPECT_EQ(FourCcToString(V4l2FourCc(PixelFormat::kYuyv)), "YUYV");
}

TEST(PixelFormatTest, GreyDecodesEachCode) {
  const std::vector<std::uint8_t> bytes = {0, 255, 128, 1};
  const Image srgb = DecodeFrame({PixelFormat::kGrey, 4, 1, 0}, bytes, ColourSpace::kSrgb);
  ASSERT_EQ(srgb.channels(), 1);
  EXPECT_FLOAT_EQ(srgb.at(0, 0, 0), 0.0f);
  EXPECT_FLOAT_EQ(srgb.at(1, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(srgb.at(2, 0, 0), Srgb(128));
  EXPECT_NEAR(srgb.at(2, 0, 0), 0.2158605, 1e-6);  // IEC 61966-2-1 at 128/255
  EXPECT_NEAR(srgb.at(3, 0, 0), (1 / 255.0) / 12.92, 1e-9);
  const Image linear = DecodeFrame({PixelFormat::kGrey, 4, 1, 0}, bytes, ColourSpace::kLinear);
  EXPECT_FLOAT_EQ(linear.at(2, 0, 0), 128 / 255.0f);
}

TEST(PixelFormatTest, Y16IsLittleEndianAndLinear) {
  const std::vector<std::uint8_t> bytes = {0x00, 0x00, 0xff, 0xff, 0x34, 0x12, 0x00, 0x80};
  // The 8-bit encoding does not apply to 16-bit data.
  const Image image = DecodeFrame({PixelFormat::kY16, 4, 1, 0}, bytes, ColourSpace::kSrgb);
  EXPECT_FLOAT_EQ(image.at(0, 0, 0), 0.0f);
  EXPECT_FLOAT_EQ(image.at(1, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(image.at(2, 0, 0), static_cast<float>(0x1234 / 65535.0));
  EXPECT_FLOAT_EQ(image.at(3, 0, 0), static_cast<float>(0x8000 / 65535.0));
}

TEST(PixelFormatTest, YuyvDecodesBt601LimitedRange) {
  // Pairs: white, black, mid grey, saturated red (BT.601: Y 81, Cb 90, Cr 240).
  const std::vector<std::uint8_t> bytes = {235, 128, 235, 128, 16, 128, 16, 128,
                                           126, 128, 126, 128, 81, 90,  81, 240};
  const Image image = DecodeFrame({PixelFormat::kYuyv, 8, 1, 0}, bytes, ColourSpace::kLinear);
  ASSERT_EQ(image.channels(), 3);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(image.at(0, 0, c), 1.0, 1e-6);
    EXPECT_NEAR(image.at(1, 0, c), 1.0, 1e-6);
    EXPECT_NEAR(image.at(2, 0, c), 0.0, 1e-6);
    EXPECT_NEAR(image.at(4, 0, c), 110 / 219.0, 1e-6);
  }
  EXPECT_NEAR(image.at(6, 0, 0), 1.0, 0.01);
  EXPECT_NEAR(image.at(6, 0, 1), 0.0, 0.01);
  EXPECT_NEAR(image.at(6, 0, 2), 0.0, 0.01);
  // sRGB-encoded video: the grey linearises.
  const Image srgb = DecodeFrame({PixelFormat::kYuyv, 8, 1, 0}, bytes, ColourSpace::kSrgb);
  EXPECT_NEAR(srgb.at(4, 0, 1), SrgbToLinear(110 / 219.0), 1e-6);
}

TEST(PixelFormatTest, RgbAndBgrBytesInOrderWithRowPadding) {
  // 2 x 2 pixels, rows padded to 8 bytes.
  const std::vector<std::uint8_t> rgb = {255, 0, 0,   0,  255, 0,  9, 9,  //
                                         0,   0, 255, 10, 20,  30, 9, 9};
  const Image a = DecodeFrame({PixelFormat::kRgb24, 2, 2, 8}, rgb, ColourSpace::kLinear);
  EXPECT_FLOAT_EQ(a.at(0, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(a.at(1, 0, 1), 1.0f);
  EXPECT_FLOAT_EQ(a.at(0, 1, 2), 1.0f);
  EXPECT_FLOAT_EQ(a.at(1, 1, 0), 10 / 255.0f);
  EXPECT_FLOAT_EQ(a.at(1, 1, 2), 30 / 255.0f);
  const Image b = DecodeFrame({PixelFormat::kBgr24, 2, 2, 8}, rgb, ColourSpace::kSrgb);
  EXPECT_FLOAT_EQ(b.at(0, 0, 2), 1.0f);  // first byte is blue
  EXPECT_FLOAT_EQ(b.at(1, 1, 0), Srgb(30));
  EXPECT_FLOAT_EQ(b.at(1, 1, 2), Srgb(10));
}

Image Patches(int width, int height) {
  // Flat colour blocks of 8 x 8 (JPEG blocks, YUYV pairs): every format can carry them.
  Image image(width, height, 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int block = (x / 8) + 3 * (y / 8);
      image.at(x, y, 0) = static_cast<float>(0.05 + 0.3 * (block % 3));
      image.at(x, y, 1) = static_cast<float>(0.1 + 0.25 * ((block / 2) % 3));
      image.at(x, y, 2) = static_cast<float>(0.7 - 0.2 * (block % 4));
    }
  }
  return image;
}

TEST(PixelFormatTest, MjpegDecodesAKnownFrame) {
  const Image truth = Patches(24, 16);
  const FrameLayout layout{PixelFormat::kMjpeg, 24, 16, 0};
  const auto jpeg = testing::EncodeFrame(layout, truth, ColourSpace::kSrgb, 100);
  ASSERT_GT(jpeg.size(), 2u);
  EXPECT_EQ(jpeg[0], 0xff);  // SOI marker
  EXPECT_EQ(jpeg[1], 0xd8);
  const Image decoded = DecodeFrame(layout, jpeg, ColourSpace::kSrgb);
  ASSERT_TRUE(decoded.SameShape(truth));
  for (std::size_t i = 0; i < truth.values().size(); ++i) {
    // Within two 8-bit codes in the encoded domain.
    ASSERT_NEAR(LinearToSrgb(decoded.values()[i]), LinearToSrgb(truth.values()[i]), 2.0 / 255)
        << "sample " << i;
  }
}

class RoundTripTest : public ::testing::TestWithParam<PixelFormat> {};

TEST_P(RoundTripTest, EncodedFramesDecodeToTheirValues) {
  const PixelFormat format = GetParam();
  const Image truth = Patches(32, 16);
  const FrameLayout layout{format, 32, 16,
                           format == PixelFormat::kMjpeg ? 0 : 32 * BytesPerPixel(format) + 4};
  const auto bytes = testing::EncodeFrame(layout, truth, ColourSpace::kSrgb);
  const Image decoded = DecodeFrame(layout, bytes, ColourSpace::kSrgb);
  ASSERT_EQ(decoded.channels(), ChannelCount(format));
  // Tolerances in the encoded domain: quantisation (8-bit: half a code; YUYV's limited range and
  // chroma: about two codes; JPEG at quality 95: a few codes).
  const double tolerance = format == PixelFormat::kY16     ? 1.0 / 65535
                           : format == PixelFormat::kMjpeg ? 4.0 / 255
                           : format == PixelFormat::kYuyv  ? 2.5 / 255
                                                           : 0.5 / 255 + 1e-6;
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 32; ++x) {
      for (int c = 0; c < decoded.channels(); ++c) {
        const double expected =
            decoded.channels() == 1
                ? (truth.at(x, y, 0) + truth.at(x, y, 1) + truth.at(x, y, 2)) / 3
                : truth.at(x, y, c);
        const double got = decoded.at(x, y, c);
        if (format == PixelFormat::kY16) {
          ASSERT_NEAR(got, expected, tolerance) << x << "," << y;
        } else {
          ASSERT_NEAR(LinearToSrgb(got), LinearToSrgb(expected), tolerance) << x << "," << y;
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllFormats, RoundTripTest,
                         ::testing::Values(PixelFormat::kGrey, PixelFormat::kY16,
                                           PixelFormat::kYuyv, PixelFormat::kMjpeg,
                                           PixelFormat::kRgb24, PixelFormat::kBgr24),
                         [](const auto& param_info) {
                           return std::string(ToString(param_info.param));
                         });

TEST(PixelFormatTest, BadFramesAreErrors) {
  const std::vector<std::uint8_t> short_frame(10, 0);
  try {
    DecodeFrame({PixelFormat::kRgb24, 4, 4, 0}, short_frame, ColourSpace::kSrgb);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("truncated: 10 bytes, expected 48"));
  }
  std::vector<std::uint8_t> not_jpeg(100, 0x42);
  EXPECT_THROW(
      {
        try {
          DecodeFrame({PixelFormat::kMjpeg, 8, 8, 0}, not_jpeg, ColourSpace::kSrgb);
        } catch (const Error& e) {
          EXPECT_THAT(e.what(), HasSubstr("corrupt MJPEG frame"));
          throw;
        }
      },
      Error);
  // A JPEG cut short loses its last rows: refused, not decoded as grey.
  const Image truth = Patches(32, 32);
  auto jpeg = testing::EncodeFrame({PixelFormat::kMjpeg, 32, 32, 0}, truth, ColourSpace::kSrgb);
  jpeg.resize(jpeg.size() / 2);
  EXPECT_THROW(DecodeFrame({PixelFormat::kMjpeg, 32, 32, 0}, jpeg, ColourSpace::kSrgb), Error);
  // A JPEG of another size than the stream's.
  const auto small =
      testing::EncodeFrame({PixelFormat::kMjpeg, 32, 32, 0}, truth, ColourSpace::kSrgb);
  try {
    DecodeFrame({PixelFormat::kMjpeg, 64, 32, 0}, small, ColourSpace::kSrgb);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("MJPEG frame is 32x32, the stream format is 64x32"));
  }
  EXPECT_THROW(DecodeFrame({PixelFormat::kYuyv, 3, 1, 0}, short_frame, ColourSpace::kSrgb), Error);
  EXPECT_THROW(DecodeFrame({PixelFormat::kFloat, 1, 1, 0}, short_frame, ColourSpace::kSrgb), Error);
}

}  // namespace
}  // namespace photomat

#include "core/image_io.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/random.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

using ::testing::HasSubstr;
using testing::SameBits;
using testing::TempDir;
using testing::WriteFile;

std::string MessageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ImageIoTest, SixteenBitPngRoundTripsEveryCodeExactly) {
  TempDir dir;
  Image image(256, 256, 1);
  for (int i = 0; i < 65536; ++i) image.values()[i] = static_cast<float>(i / 65535.0);
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint16;
  WriteImage(dir / "all.png", image, options);
  const LoadedImage loaded = ReadImage(dir / "all.png");
  EXPECT_EQ(loaded.info.bits_per_sample, 16);
  EXPECT_EQ(loaded.info.colour_space, ColourSpace::kLinear);
  for (int i = 0; i < 65536; ++i) {
    ASSERT_EQ(std::lround(loaded.image.values()[i] * 65535.0), i) << "code " << i;
  }
  EXPECT_EQ(loaded.info.saturated_pixels, 1u);  // only code 65535
}

TEST(ImageIoTest, SixteenBitTiffIsReadAtFullPrecision) {
  TempDir dir;
  Image image(3, 2, 3);
  for (std::size_t i = 0; i < image.values().size(); ++i) {
    image.values()[i] = static_cast<float>((i * 3851 + 17) % 65536 / 65535.0);
  }
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint16;
  WriteImage(dir / "x.tif", image, options);
  const LoadedImage loaded = ReadImage(dir / "x.tif");
  EXPECT_EQ(loaded.info.bits_per_sample, 16);
  for (std::size_t i = 0; i < image.values().size(); ++i) {
    EXPECT_EQ(loaded.image.values()[i], image.values()[i]);
  }
}

TEST(ImageIoTest, EightBitIsDecodedAsSrgbByDefault) {
  TempDir dir;
  Image image(2, 1, 1);
  image.values()[0] = 0.5f;  // linear
  image.values()[1] = 0.0f;
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint8;
  options.encoding = ColourSpace::kSrgb;
  WriteImage(dir / "srgb.png", image, options);
  const LoadedImage loaded = ReadImage(dir / "srgb.png");
  EXPECT_EQ(loaded.info.colour_space, ColourSpace::kSrgb);
  // sRGB code round(255 * 0.7354) = 188 decodes to 0.5029.
  EXPECT_NEAR(loaded.image.values()[0], 0.5, 0.005);
  ImageReadOptions linear;
  linear.colour_space = ColourSpace::kLinear;
  EXPECT_NEAR(ReadImage(dir / "srgb.png", linear).image.values()[0], 188 / 255.0, 1e-6);
}

TEST(ImageIoTest, ExrKeepsFloatsChannelNamesAndAttributes) {
  TempDir dir;
  Image image(3, 2, std::vector<std::string>{"normal.X", "normal.Y", "normal.Z", "albedo.R"});
  for (std::size_t i = 0; i < image.values().size(); ++i) {
    image.values()[i] = -1.5f + 0.123456789f * static_cast<float>(i);
  }
  ImageWriteOptions options;
  options.attributes["photomat:test"] = "{\"a\": 1}";
  WriteImage(dir / "stack.exr", image, options);
  ImageReadOptions keep;
  keep.keep_alpha = true;
  const LoadedImage loaded = ReadImage(dir / "stack.exr", keep);
  ASSERT_TRUE(loaded.image.SameShape(image));
  EXPECT_EQ(loaded.info.attributes.at("photomat:test"), "{\"a\": 1}");
  // OpenEXR stores channels sorted by name; photomat finds them by name.
  for (const std::string& name : image.channel_names()) {
    const int in = image.FindChannel(name), out = loaded.image.FindChannel(name);
    ASSERT_GE(out, 0) << name;
    for (std::size_t p = 0; p < image.pixel_count(); ++p) {
      EXPECT_EQ(loaded.image.pixel(p)[out], image.pixel(p)[in]);
    }
  }
}

constexpr std::array<ExrCompression, 5> kEveryExrCompression = {
    ExrCompression::kNone, ExrCompression::kRle, ExrCompression::kZips, ExrCompression::kZip,
    ExrCompression::kPiz};

// Random float bit patterns (every finite value is as likely as its share of the encodings, so
// denormals and both zeros occur), then the extremes at fixed places.
Image RandomFloatBits(int width, int height, int channels, std::uint64_t seed) {
  Image image(width, height, channels);
  Random random(seed);
  for (float& value : image.values()) {
    do {
      const auto bits = static_cast<std::uint32_t>(random.Index(std::uint64_t{1} << 32));
      std::memcpy(&value, &bits, sizeof value);
    } while (!std::isfinite(value));
  }
  constexpr float kExtremes[] = {-0.0f,
                                 0.0f,
                                 std::numeric_limits<float>::denorm_min(),
                                 -std::numeric_limits<float>::denorm_min(),
                                 std::numeric_limits<float>::min() / 3.0f,  // a denormal
                                 std::numeric_limits<float>::min(),
                                 std::numeric_limits<float>::max(),
                                 std::numeric_limits<float>::lowest(),
                                 1e-30f,
                                 -3e37f};
  for (std::size_t i = 0; i < std::size(kExtremes); ++i) image.values()[i * 7] = kExtremes[i];
  return image;
}

// The images compared bit for bit are named in sorted order (EXR sorts channels by name), so
// the planes read back in place.
TEST(ImageIoTest, EveryExrCompressionStoresFloatBitsExactly) {
  TempDir dir;
  const Image image = RandomFloatBits(61, 47, 5, 18);
  for (const ExrCompression compression : kEveryExrCompression) {
    SCOPED_TRACE(std::string(ToString(compression)));
    ImageWriteOptions options;
    options.exr_compression = compression;
    const fs::path path = dir / (std::string(ToString(compression)) + ".exr");
    WriteImage(path, image, options);
    ImageReadOptions keep;
    keep.keep_alpha = true;
    const LoadedImage loaded = ReadImage(path, keep);
    EXPECT_EQ(loaded.info.attributes.at("compression"), ToString(compression));
    EXPECT_TRUE(SameBits(loaded.image, image));
  }
}

TEST(ImageIoTest, ExrWrittenInSeveralBandsStoresFloatBitsExactly) {
  // One 8 KiB float row: a 16 MiB band is 2048 rows, so 2100 rows take two write calls.
  TempDir dir;
  const Image image = RandomFloatBits(2048, 2100, 1, 7);
  WriteImage(dir / "tall.exr", image);
  EXPECT_TRUE(SameBits(ReadImage(dir / "tall.exr").image, image));
}

TEST(ImageIoTest, ExrFilesAreTheSameOnOneAndTwoThreads) {
  // OpenImageIO stamps the wall-clock second into "DateTime" (EXR's capDate); pinning it leaves
  // the files comparable byte for byte.
  TempDir dir;
  const Image image = RandomFloatBits(300, 260, 4, 3);
  for (const ExrCompression compression : kEveryExrCompression) {
    SCOPED_TRACE(std::string(ToString(compression)));
    ImageWriteOptions options;
    options.exr_compression = compression;
    options.attributes["DateTime"] = "2000:01:01 00:00:00";
    std::string bytes[2];
    for (const int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      const fs::path path = dir / fmt::format("{}.exr", threads);
      WriteImage(path, image, options);
      bytes[threads - 1] = ReadTextFile(path);
    }
    ASSERT_FALSE(bytes[0].empty());
    EXPECT_TRUE(bytes[0] == bytes[1]);
  }
}

TEST(ImageIoTest, UnknownExrCompressionNamesTheAllowedOnes) {
  EXPECT_EQ(ParseExrCompression("piz"), ExrCompression::kPiz);
  for (const ExrCompression compression : kEveryExrCompression) {
    EXPECT_EQ(ParseExrCompression(ToString(compression)), compression);
  }
  // b44 and dwa exist in OpenEXR but lose float bits: not offered.
  for (const char* name : {"b44", "dwaa", "ZIP", ""}) {
    EXPECT_EQ(MessageOf([&] { ParseExrCompression(name); }),
              fmt::format("unknown EXR compression '{}' (none, rle, zips, zip or piz)", name));
  }
}

TEST(ImageIoTest, TiledFilesAndManyBandsReadIntoPlanes) {
  // Files are decoded band by band (64 rows, or a row of tiles) into the planes: a tiled TIFF
  // whose tiles do not divide the image, and a scanline file of several bands.
  TempDir dir;
  const int width = 70, height = 150, channels = 3;
  std::vector<std::uint16_t> codes(static_cast<std::size_t>(width) * height * channels);
  for (std::size_t i = 0; i < codes.size(); ++i) codes[i] = static_cast<std::uint16_t>(i * 37);
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT16);
  spec.tile_width = 32;
  spec.tile_height = 16;
  const std::string tiled = (dir / "tiled.tif").string();
  auto output = OIIO::ImageOutput::create(tiled);
  ASSERT_TRUE(output && output->open(tiled, spec));
  ASSERT_TRUE(output->write_image(OIIO::TypeDesc::UINT16, codes.data()));
  ASSERT_TRUE(output->close());
  const LoadedImage loaded = ReadImage(tiled);
  ASSERT_EQ(loaded.image.width(), width);
  ASSERT_EQ(loaded.image.height(), height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) {
        const std::size_t i = (static_cast<std::size_t>(y) * width + x) * channels + c;
        ASSERT_EQ(std::lround(loaded.image.at(x, y, c) * 65535.0), codes[i]) << x << " " << y;
      }
    }
  }
  // Written back as scanlines and read again: the same values.
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint16;
  WriteImage(dir / "lines.png", loaded.image, options);
  const Image again = ReadImage(dir / "lines.png").image;
  EXPECT_TRUE(
      std::equal(again.values().begin(), again.values().end(), loaded.image.values().begin()));
}

TEST(ImageIoTest, SolidTexturesAreNotPictures) {
  TempDir dir;
  EXPECT_THAT(MessageOf([&] {
                WriteImage(dir / "v.exr", Image(ImageExtent{2, 2, 2}, 1));
              }),
              HasSubstr("2x2x2"));
}

TEST(ImageIoTest, MissingFileIsNamed) {
  EXPECT_THAT(MessageOf([] { ReadImage("/nonexistent/x.png"); }),
              HasSubstr("/nonexistent/x.png: image file not found"));
}

TEST(ImageIoTest, CorruptImageIsNamed) {
  TempDir dir;
  testing::WriteFile(dir / "bad.png", "\x89PNG\r\n\x1a\nthis is not a png");
  EXPECT_THAT(MessageOf([&] { ReadImage(dir / "bad.png"); }), HasSubstr("bad.png"));
}

// A 64 x 48 RGB ramp written as `name` with `type` samples, and a copy of it cut to `kept` of its
// bytes, "cut" with the same extension, whose path is returned.
fs::path WriteImageCutShort(const TempDir& dir, const std::string& name, SampleType type,
                            double kept) {
  Image image(64, 48, 3);
  for (std::size_t i = 0; i < image.values().size(); ++i) image.values()[i] = (i % 89) / 89.0f;
  ImageWriteOptions options;
  options.sample_type = type;
  WriteImage(dir / name, image, options);
  EXPECT_EQ(ReadImage(dir / name).image.width(), 64);
  const std::string bytes = ReadTextFile(dir / name);
  const fs::path cut = dir / ("cut" + fs::path(name).extension().string());
  WriteFile(cut, bytes.substr(0, static_cast<std::size_t>(bytes.size() * kept)));
  return cut;
}

TEST(ImageIoTest, TruncatedImageIsAnErrorNotAPartialImage) {
  TempDir dir;
  const fs::path cut = WriteImageCutShort(dir, "full.png", SampleType::kUint16, 0.5);
  const std::string message = MessageOf([&] { ReadImage(cut); });
  EXPECT_THAT(message, HasSubstr("cut.png"));
  // One line: OpenImageIO's PNG reader gives three messages for this fault, joined by "; ".
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_THAT(message, HasSubstr("hit end of file"));
}

// libjpeg decodes a JPEG cut short with a warning only, its missing rows grey; photomat refuses it
// (FindJpegTruncation) before any pixel is used.
TEST(ImageIoTest, TruncatedJpegIsAnErrorNotGreyRows) {
  TempDir dir;
  const fs::path cut = WriteImageCutShort(dir, "whole.jpg", SampleType::kUint8, 2.0 / 3.0);
  const std::string message = MessageOf([&] { ReadImage(cut); });
  EXPECT_THAT(message, HasSubstr(cut.string() + ": truncated JPEG: the file ends at byte"));
  EXPECT_THAT(message, HasSubstr("it is cut short"));
}

TEST(ImageIoTest, NanInFloatImageIsRejected) {
  TempDir dir;
  Image image(2, 2, 1);
  image.values()[3] = NAN;
  WriteImage(dir / "nan.exr", image);
  EXPECT_THAT(MessageOf([&] { ReadImage(dir / "nan.exr"); }), HasSubstr("NaN or infinite"));
}

TEST(ImageIoTest, AlphaIsDroppedForPhotometricData) {
  TempDir dir;
  Image image(2, 2, 4);
  for (float& v : image.values()) v = 1.0f;
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint8;
  WriteImage(dir / "rgba.png", image, options);
  // PNG writers mark the fourth channel as alpha.
  EXPECT_EQ(ReadImage(dir / "rgba.png").image.channels(), 3);
}

// Writes `image` as a PNG of `type` codes (value x largest code, rounded) exactly as given: alpha
// unassociated, the colours not divided by it (as cameras and most tools store PNGs).
void WriteUnassociatedPng(const fs::path& path, const Image& image, OIIO::TypeDesc type) {
  const int channels = image.channels();
  OIIO::ImageSpec spec(image.width(), image.height(), channels, type);
  spec.attribute("oiio:UnassociatedAlpha", 1);
  if (channels == 2 || channels == 4) spec.alpha_channel = channels - 1;
  std::vector<float> interleaved;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      for (int c = 0; c < channels; ++c) interleaved.push_back(image.at(x, y, c));
    }
  }
  auto out = OIIO::ImageOutput::create(path.string());
  ASSERT_TRUE(out && out->open(path.string(), spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, interleaved.data()));
  ASSERT_TRUE(out->close());
}

// Every channel layout the decoder specialises (grey, RGB, RGBA without its alpha) and the
// general one (grey + alpha, RGBA kept whole), at 8 and 16 bits: each code decodes to its linear
// value, colours are read as stored whatever the alpha (not multiplied by it), and a pixel counts
// as clipped when a kept channel is at the largest code.
TEST(ImageIoTest, EveryChannelLayoutDecodesCodesAndCountsClippedPixels) {
  TempDir dir;
  for (const OIIO::TypeDesc type : {OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT16}) {
    const double largest = type == OIIO::TypeDesc::UINT8 ? 255.0 : 65535.0;
    for (const int channels : {1, 2, 3, 4}) {
      // 7 x 3 pixels, code (x + 7 y + 5 c) % 50 + 1 (alpha too: below 1); pixel (x, 1) has
      // channel x % channels at the largest code, for x < 4.
      Image image(7, 3, channels);
      for (int c = 0; c < channels; ++c) {
        for (int y = 0; y < 3; ++y) {
          for (int x = 0; x < 7; ++x) {
            image.at(x, y, c) = static_cast<float>(((x + 7 * y + 5 * c) % 50 + 1) / largest);
          }
        }
      }
      for (int x = 0; x < 4; ++x) image.at(x, 1, x % channels) = 1.0f;
      const fs::path path = dir / fmt::format("c{}_{}.png", channels, largest);
      WriteUnassociatedPng(path, image, type);
      ImageReadOptions read;
      read.colour_space = ColourSpace::kLinear;
      const LoadedImage loaded = ReadImage(path, read);
      const int kept = channels == 2 || channels == 4 ? channels - 1 : channels;  // alpha dropped
      ASSERT_EQ(loaded.image.channels(), kept) << path;
      for (int c = 0; c < kept; ++c) {
        for (int y = 0; y < 3; ++y) {
          for (int x = 0; x < 7; ++x) {
            ASSERT_EQ(std::lround(loaded.image.at(x, y, c) * largest),
                      std::lround(image.at(x, y, c) * largest))
                << path << " channel " << c << " at " << x << "," << y;
          }
        }
      }
      std::size_t clipped = 0;  // a largest code in the dropped alpha does not count
      for (int x = 0; x < 4; ++x) clipped += x % channels < kept ? 1 : 0;
      EXPECT_EQ(loaded.info.saturated_pixels, clipped) << path;
      // Kept whole (stacks, masks): every channel, alpha as stored; the colours in OpenImageIO's
      // associated convention (multiplied by the alpha, below 1 here), so only a largest code in
      // the alpha stays at the largest code.
      read.keep_alpha = true;
      const LoadedImage whole = ReadImage(path, read);
      ASSERT_EQ(whole.image.channels(), channels) << path;
      const bool alpha = kept < channels;
      std::size_t whole_clipped = 0;
      for (int x = 0; x < 4; ++x) whole_clipped += !alpha || x % channels == kept ? 1 : 0;
      EXPECT_EQ(whole.info.saturated_pixels, whole_clipped) << path;
      for (int x = 0; alpha && x < 7; ++x) {
        EXPECT_EQ(std::lround(whole.image.at(x, 0, kept) * largest),
                  std::lround(image.at(x, 0, kept) * largest))
            << path;
      }
    }
  }
}

TEST(ImageIoTest, MaskThresholdsAtHalf) {
  TempDir dir;
  Image image(3, 1, 1);
  image.values()[0] = 0.2f;
  image.values()[1] = 0.6f;
  image.values()[2] = 1.0f;
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint8;
  WriteImage(dir / "mask.png", image, options);
  const Mask mask = ReadMask(dir / "mask.png");
  EXPECT_FALSE(mask(0, 0));
  EXPECT_TRUE(mask(1, 0));
  EXPECT_TRUE(mask(2, 0));
}

TEST(ImageIoTest, FailedWriteLeavesNoFile) {
  TempDir dir;
  Image image(2, 2, 1);
  image.values()[0] = NAN;
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint8;
  EXPECT_THROW(WriteImage(dir / "x.png", image, options), Error);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(ImageIoDeathTest, FullDiskIsAnErrorAndLeavesNoFile) {
  TempDir dir;
  Image image(512, 512, 3);
  for (std::size_t i = 0; i < image.values().size(); ++i) image.values()[i] = (i % 101) / 101.0f;
  EXPECT_EXIT(
      {
        testing::LimitFileSize(20000);
        try {
          WriteImage(dir / "big.exr", image);
        } catch (const Error& e) {
          const bool named = std::string(e.what()).find("big.exr") != std::string::npos;
          _exit(named && std::filesystem::is_empty(dir.path()) ? 0 : 2);
        }
        _exit(1);
      },
      ::testing::ExitedWithCode(0), "");
}

TEST(ImageIoTest, ReadsRealSixteenBitDiligentImage) {
  PHOTOMAT_TEST_DATA_OR_SKIP(file, "diligent/ball/001.png");
  const LoadedImage loaded = ReadImage(file);
  EXPECT_EQ(loaded.image.width(), 612);
  EXPECT_EQ(loaded.image.height(), 512);
  EXPECT_EQ(loaded.image.channels(), 3);
  EXPECT_EQ(loaded.info.bits_per_sample, 16);
  EXPECT_GT(loaded.info.saturated_pixels, 0u);  // the README: highlights reach 65535
}

TEST(ImageIoTest, ReadableImageFileNamesComeFromOpenImageIoPlugins) {
  for (const char* name :
       {"a.png", "b.TIF", "c.tiff", "d.exr", "e.JPG", "f.jpeg", "g.pgm", "dir/with space/h.Png"}) {
    EXPECT_TRUE(IsReadableImageFileName(name)) << name;
  }
  for (const char* name :
       {"lights.lp", "manifest.json", "notes.txt", "png", "a.png.bak", "x.null", "no_extension"}) {
    EXPECT_FALSE(IsReadableImageFileName(name)) << name;
  }
}

TEST(ImageIoTest, NaturalOrderComparesDigitRunsAsNumbers) {
  EXPECT_TRUE(NaturalLess("img.2.png", "img.10.png"));
  EXPECT_FALSE(NaturalLess("img.10.png", "img.2.png"));
  EXPECT_TRUE(NaturalLess("img_002.png", "img_10.png"));  // padding does not matter
  EXPECT_TRUE(NaturalLess("a9b", "a10a"));
  EXPECT_TRUE(NaturalLess("a", "b"));
  EXPECT_TRUE(NaturalLess("img", "img1"));               // a prefix first
  EXPECT_FALSE(NaturalLess("img.png", "img.png"));       // strict
  EXPECT_FALSE(NaturalLess("img10.png", "img010.png"));  // equal numbers: neither is less...
  EXPECT_FALSE(NaturalLess("img010.png", "img10.png"));  // ...either way
}

TEST(ImageIoTest, ListsTheImageFilesOfAFolderInNaturalOrder) {
  TempDir dir;
  for (const char* name : {"frame10.png", "frame2.PNG", "frame1.exr", "lights.lp", "notes.txt"}) {
    WriteFile(dir / name, "x");  // listing looks at names only
  }
  std::filesystem::create_directory(dir / "sub.png");  // a folder, whatever its name
  std::filesystem::create_symlink(dir / "gone.png", dir / "dangling.png");
  std::vector<std::string> names;
  for (const auto& file : ListImageFiles(dir.path())) names.push_back(file.filename().string());
  EXPECT_EQ(names, (std::vector<std::string>{"frame1.exr", "frame2.PNG", "frame10.png"}));
  std::filesystem::create_directory(dir / "empty");
  EXPECT_TRUE(ListImageFiles(dir / "empty").empty());
  EXPECT_THROW(ListImageFiles(dir / "missing"), Error);
  EXPECT_THROW(ListImageFiles(dir / "lights.lp"), Error);
}

}  // namespace
}  // namespace photomat

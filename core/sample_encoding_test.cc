#include "core/sample_encoding.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <lcms2.h>
#include <png.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <vector>

#include "core/image_band_io.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// ---- independent closed forms (none of them calls the code under test) ----------------------

double SrgbDecoded(double c) {
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

// RGB -> XYZ of a set of primaries with white Y = 1 (the textbook construction).
Eigen::Matrix3d PrimariesToXyz(double rx, double ry, double gx, double gy, double bx, double by,
                               double wx, double wy) {
  const auto xyz = [](double x, double y) { return Eigen::Vector3d(x / y, 1.0, (1 - x - y) / y); };
  Eigen::Matrix3d p;
  p << xyz(rx, ry), xyz(gx, gy), xyz(bx, by);
  const Eigen::Vector3d s = p.inverse() * xyz(wx, wy);
  return p * s.asDiagonal();
}

Eigen::Matrix3d Rec709ToXyz() {
  return PrimariesToXyz(0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290);
}

// ---- test files -----------------------------------------------------------------------------

// The codes of `width` RGB pixels: channel c of pixel k is (k * step + c * shift) mod (max + 1).
std::vector<std::uint16_t> Codes(int width, int bits, int step, int shift) {
  const int levels = 1 << bits;
  std::vector<std::uint16_t> codes(static_cast<std::size_t>(width) * 3);
  for (int k = 0; k < width; ++k) {
    for (int c = 0; c < 3; ++c)
      codes[3 * k + c] = static_cast<std::uint16_t>((k * step + c * shift) % levels);
  }
  return codes;
}

struct PngTags {
  bool srgb = false;
  std::optional<png_fixed_point> gama;  // as stored: 45455 for a 2.2 curve
  std::vector<unsigned char> icc;
};
PngTags SrgbChunk() {
  PngTags tags;
  tags.srgb = true;
  return tags;
}
PngTags GamaChunk(png_fixed_point stored) {
  PngTags tags;
  tags.gama = stored;
  return tags;
}
PngTags IccChunk(std::vector<unsigned char> profile) {
  PngTags tags;
  tags.icc = std::move(profile);
  return tags;
}

// One row of RGB codes as an 8- or 16-bit PNG with exactly the colour chunks `tags` asks for
// (libpng's default error handling aborts the test on failure).
void WritePng(const fs::path& path, const std::vector<std::uint16_t>& codes, int bits,
              const PngTags& tags) {
  const int width = static_cast<int>(codes.size() / 3);
  std::FILE* file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, file);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), 1, bits, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (tags.srgb) png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  if (tags.gama) png_set_gAMA_fixed(png, info, *tags.gama);
  if (!tags.icc.empty()) {
    png_set_iCCP(png, info, "test profile", PNG_COMPRESSION_TYPE_BASE, tags.icc.data(),
                 static_cast<png_uint_32>(tags.icc.size()));
  }
  png_write_info(png, info);
  std::vector<png_byte> row;
  for (const std::uint16_t code : codes) {
    if (bits == 16) row.push_back(static_cast<png_byte>(code >> 8));
    row.push_back(static_cast<png_byte>(code & 0xff));
  }
  png_write_row(png, row.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
}

// Adobe RGB (1998) made with Little CMS: its primaries, D65 white and the 563/256 power curve.
std::vector<unsigned char> AdobeRgbProfile() {
  const cmsCIExyY d65 = {0.3127, 0.3290, 1.0};
  const cmsCIExyYTRIPLE primaries = {{0.64, 0.33, 1.0}, {0.21, 0.71, 1.0}, {0.15, 0.06, 1.0}};
  cmsToneCurve* curve = cmsBuildGamma(nullptr, 563.0 / 256.0);
  cmsToneCurve* curves[3] = {curve, curve, curve};
  cmsHPROFILE profile = cmsCreateRGBProfile(&d65, &primaries, curves);
  cmsMLU* description = cmsMLUalloc(nullptr, 1);
  cmsMLUsetASCII(description, "en", "US", "Adobe RGB (1998) test");
  cmsWriteTag(profile, cmsSigProfileDescriptionTag, description);
  cmsMLUfree(description);
  cmsFreeToneCurve(curve);
  cmsUInt32Number size = 0;
  cmsSaveProfileToMem(profile, nullptr, &size);
  std::vector<unsigned char> bytes(size);
  cmsSaveProfileToMem(profile, bytes.data(), &size);
  cmsCloseProfile(profile);
  return bytes;
}

std::vector<unsigned char> SrgbProfile() {
  cmsHPROFILE profile = cmsCreate_sRGBProfile();
  cmsUInt32Number size = 0;
  cmsSaveProfileToMem(profile, nullptr, &size);
  std::vector<unsigned char> bytes(size);
  cmsSaveProfileToMem(profile, bytes.data(), &size);
  cmsCloseProfile(profile);
  return bytes;
}

// Largest |decoded - expected(code)| over every sample, expected from a per-channel closed form.
template <typename Expected>
double WorstError(const Image& image, const std::vector<std::uint16_t>& codes, Expected expected) {
  double worst = 0.0;
  for (int k = 0; k < image.width(); ++k) {
    for (int c = 0; c < 3; ++c) {
      worst = std::max(worst, std::abs(image.at(k, 0, c) - expected(codes[3 * k + c])));
    }
  }
  return worst;
}

// ---- one test per metadata case -------------------------------------------------------------

TEST(SampleEncodingTest, UntaggedEightBitPngIsSrgbByDefaultOrAsTheManifestSays) {
  TempDir dir;
  const auto codes = Codes(256, 8, 1, 85);
  WritePng(dir / "plain.png", codes, 8, {});
  const LoadedImage loaded = ReadImage(dir / "plain.png");
  EXPECT_EQ(loaded.info.encoding.decided_by, "default");
  EXPECT_EQ(loaded.info.encoding.Name(), "srgb");
  // Measured 2.9e-8 (float rounding of the exact curve); bound 1e-6 = 34x.
  EXPECT_LT(WorstError(loaded.image, codes, [](int v) { return SrgbDecoded(v / 255.0); }), 1e-6);

  ImageReadOptions untagged;
  untagged.untagged_colour_space = ColourSpace::kLinear;
  const LoadedImage linear = ReadImage(dir / "plain.png", untagged);
  EXPECT_EQ(linear.info.encoding.decided_by, "untagged-option");
  // Measured 3.0e-8; bound 1e-6.
  EXPECT_LT(WorstError(linear.image, codes, [](int v) { return v / 255.0; }), 1e-6);
}

TEST(SampleEncodingTest, UntaggedSixteenBitPngIsLinearByDefault) {
  TempDir dir;
  const auto codes = Codes(1024, 16, 64, 21845);
  WritePng(dir / "plain16.png", codes, 16, {});
  const LoadedImage loaded = ReadImage(dir / "plain16.png");
  EXPECT_EQ(loaded.info.encoding.decided_by, "default");
  EXPECT_EQ(loaded.info.encoding.Name(), "linear");
  // Measured 3.0e-8; bound 1e-6.
  EXPECT_LT(WorstError(loaded.image, codes, [](int v) { return v / 65535.0; }), 1e-6);
}

TEST(SampleEncodingTest, SixteenBitPngWithAnSrgbChunkIsLinearised) {
  TempDir dir;
  const auto codes = Codes(1024, 16, 64, 21845);
  WritePng(dir / "srgb16.png", codes, 16, SrgbChunk());
  ImageReadOptions untagged;  // a tag wins over the manifest's value for untagged images
  untagged.untagged_colour_space = ColourSpace::kLinear;
  const LoadedImage loaded = ReadImage(dir / "srgb16.png", untagged);
  EXPECT_EQ(loaded.info.encoding.decided_by, "png-srgb");
  EXPECT_EQ(loaded.info.colour_space, ColourSpace::kSrgb);
  // Measured 3.0e-8; bound 1e-6. (Read as linear the error would be 0.33.)
  EXPECT_LT(WorstError(loaded.image, codes, [](int v) { return SrgbDecoded(v / 65535.0); }), 1e-6);
}

TEST(SampleEncodingTest, PngGamaOf045455DecodesAsAPureGamma22Curve) {
  TempDir dir;
  const auto codes = Codes(256, 8, 1, 85);
  WritePng(dir / "gamma22.png", codes, 8, GamaChunk(45455));
  const LoadedImage loaded = ReadImage(dir / "gamma22.png");
  EXPECT_EQ(loaded.info.encoding.decided_by, "png-gama");
  EXPECT_EQ(loaded.info.encoding.evidence, "PNG gAMA 0.45455");
  // Measured 3.0e-8; bound 1e-6. (The sRGB curve is up to 9.4e-3 away from this one.)
  EXPECT_LT(
      WorstError(loaded.image, codes, [](int v) { return std::pow(v / 255.0, 1.0 / 0.45455); }),
      1e-6);
}

TEST(SampleEncodingTest, EightBitPngWithGamaOneIsLinear) {
  TempDir dir;
  const auto codes = Codes(256, 8, 1, 85);
  WritePng(dir / "gamma1.png", codes, 8, GamaChunk(100000));
  const LoadedImage loaded = ReadImage(dir / "gamma1.png");
  EXPECT_EQ(loaded.info.encoding.Name(), "linear");
  EXPECT_EQ(loaded.info.colour_space, ColourSpace::kLinear);
  // Measured 3.0e-8; bound 1e-6.
  EXPECT_LT(WorstError(loaded.image, codes, [](int v) { return v / 255.0; }), 1e-6);
}

// Adobe RGB decoded by hand: the 563/256 power curve, then Adobe RGB -> XYZ -> linear Rec.709
// (both D65, so no white adaptation). Codes are kept in the Rec.709 gamut (every output >= 0).
double MaxAdobeError(const Image& image, const std::vector<std::uint16_t>& codes, double max) {
  const Eigen::Matrix3d to_rec709 =
      Rec709ToXyz().inverse() * PrimariesToXyz(0.64, 0.33, 0.21, 0.71, 0.15, 0.06, 0.3127, 0.3290);
  double worst = 0.0;
  for (int k = 0; k < image.width(); ++k) {
    Eigen::Vector3d adobe;
    for (int c = 0; c < 3; ++c) adobe[c] = std::pow(codes[3 * k + c] / max, 563.0 / 256.0);
    const Eigen::Vector3d expected = to_rec709 * adobe;
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(image.at(k, 0, c) - expected[c]));
  }
  return worst;
}

// Near-grey codes (each channel within 40 codes of the pixel's first), so that the Adobe RGB
// colours stay inside the Rec.709 gamut.
std::vector<std::uint16_t> NearGreyCodes(int width, int bits) {
  const int max = (1 << bits) - 1;
  std::vector<std::uint16_t> codes(static_cast<std::size_t>(width) * 3);
  for (int k = 0; k < width; ++k) {
    const int base = 40 + k * (max - 80) / (width - 1);
    const int offsets[3] = {0, (k % 7) * 5 - 15, (k % 5) * 8 - 16};
    for (int c = 0; c < 3; ++c) {
      codes[3 * k + c] = static_cast<std::uint16_t>(base + offsets[c] * (max / 255));
    }
  }
  return codes;
}

// A 16-bit RGB TIFF of `codes` (interleaved, row by row) tagged with the Adobe RGB profile
// (OpenImageIO's "ICCProfile").
void WriteAdobeRgbTiff(const std::filesystem::path& path, int width, int height,
                       const std::vector<std::uint16_t>& codes) {
  auto out = OIIO::ImageOutput::create(path.string());
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT16);
  const std::vector<unsigned char> profile = AdobeRgbProfile();
  spec.attribute("ICCProfile", OIIO::TypeDesc(OIIO::TypeDesc::UINT8, profile.size()),
                 profile.data());
  ASSERT_TRUE(out->open(path.string(), spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT16, codes.data()));
  ASSERT_TRUE(out->close());
}

TEST(SampleEncodingTest, AdobeRgbIccProfileIsLinearisedThroughTheProfile) {
  TempDir dir;
  const auto codes = NearGreyCodes(200, 16);
  WritePng(dir / "adobe.png", codes, 16, IccChunk(AdobeRgbProfile()));
  const LoadedImage png = ReadImage(dir / "adobe.png");
  EXPECT_EQ(png.info.encoding.decided_by, "icc-profile");
  EXPECT_EQ(png.info.encoding.Name(), "icc 'Adobe RGB (1998) test'");
  const double png_error = MaxAdobeError(png.image, codes, 65535.0);
  // Measured 2.26e-5 (the profile stores its colorants as s15.16 fixed point, steps of 1.5e-5);
  // bound 5e-5 = 2.2x, far below the change of primaries (taking the file as sRGB: 0.1 off).
  EXPECT_LT(png_error, 5e-5);

  // The same profile in a TIFF (OpenImageIO's "ICCProfile").
  ASSERT_NO_FATAL_FAILURE(WriteAdobeRgbTiff(dir / "adobe.tif", 200, 1, codes));
  const LoadedImage tiff = ReadImage(dir / "adobe.tif");
  EXPECT_EQ(tiff.info.encoding.decided_by, "icc-profile");
  // Measured 2.26e-5; bound 5e-5.
  EXPECT_LT(MaxAdobeError(tiff.image, codes, 65535.0), 5e-5);
}

TEST(SampleEncodingTest, PlainSrgbIccProfileDecodesAsSrgb) {
  TempDir dir;
  const auto codes = Codes(256, 8, 1, 85);
  WritePng(dir / "srgb_icc.png", codes, 8, IccChunk(SrgbProfile()));
  const LoadedImage loaded = ReadImage(dir / "srgb_icc.png");
  EXPECT_EQ(loaded.info.encoding.decided_by, "icc-profile");
  EXPECT_EQ(loaded.info.encoding.Name(), "srgb");
  // Measured 3.0e-8; bound 1e-6.
  EXPECT_LT(WorstError(loaded.image, codes, [](int v) { return SrgbDecoded(v / 255.0); }), 1e-6);
}

TEST(SampleEncodingTest, TiffExifColorSpaceDecides) {
  TempDir dir;
  const auto codes = Codes(256, 8, 1, 85);
  std::vector<std::uint8_t> samples(codes.begin(), codes.end());
  for (const int exif : {1, 65535}) {
    const fs::path path = dir / fmt::format("exif{}.tif", exif);
    auto out = OIIO::ImageOutput::create("tif");
    OIIO::ImageSpec spec(256, 1, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("Exif:ColorSpace", exif);
    ASSERT_TRUE(out->open(path.string(), spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, samples.data()));
    ASSERT_TRUE(out->close());
    ImageReadOptions untagged;
    untagged.untagged_colour_space = ColourSpace::kLinear;
    const LoadedImage loaded = ReadImage(path, untagged);
    if (exif == 1) {
      EXPECT_EQ(loaded.info.encoding.decided_by, "exif-colorspace");
      EXPECT_LT(WorstError(loaded.image, codes, [](int v) { return SrgbDecoded(v / 255.0); }),
                1e-6);  // measured 3.0e-8
    } else {            // "uncalibrated" says nothing: the value for untagged images applies
      EXPECT_EQ(loaded.info.encoding.decided_by, "untagged-option");
      EXPECT_LT(WorstError(loaded.image, codes, [](int v) { return v / 255.0; }), 1e-6);
    }
  }
}

void WriteExr(const fs::path& path, const Image& image,
              const std::array<float, 8>& chromaticities) {
  auto out = OIIO::ImageOutput::create("exr");
  OIIO::ImageSpec spec(image.width(), 1, 3, OIIO::TypeDesc::FLOAT);
  spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), chromaticities.data());
  ASSERT_TRUE(out->open(path.string(), spec));
  std::vector<float> samples;
  for (int k = 0; k < image.width(); ++k) {
    for (int c = 0; c < 3; ++c) samples.push_back(image.at(k, 0, c));
  }
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, samples.data()));
  ASSERT_TRUE(out->close());
}

TEST(SampleEncodingTest, ExrWithDisplayP3ChromaticitiesIsConvertedToRec709Primaries) {
  TempDir dir;
  Image image(64, 1, 3);
  for (int k = 0; k < 64; ++k) {
    for (int c = 0; c < 3; ++c)
      image.at(k, 0, c) = 0.2f + 0.01f * static_cast<float>((k * (c + 3)) % 50);
  }
  const std::array<float, 8> p3 = {0.680f, 0.320f, 0.265f,  0.690f,
                                   0.150f, 0.060f, 0.3127f, 0.3290f};
  WriteExr(dir / "p3.exr", image, p3);
  const LoadedImage loaded = ReadImage(dir / "p3.exr");
  EXPECT_EQ(loaded.info.encoding.Name(), "linear + chromaticities");
  const Eigen::Matrix3d to_rec709 =
      Rec709ToXyz().inverse() *
      PrimariesToXyz(0.680, 0.320, 0.265, 0.690, 0.150, 0.060, 0.3127, 0.3290);
  double worst = 0.0, change = 0.0;
  for (int k = 0; k < 64; ++k) {
    const Eigen::Vector3d in(image.at(k, 0, 0), image.at(k, 0, 1), image.at(k, 0, 2));
    const Eigen::Vector3d expected = to_rec709 * in;
    for (int c = 0; c < 3; ++c) {
      worst = std::max(worst, std::abs(loaded.image.at(k, 0, c) - expected[c]));
      change = std::max(change, std::abs(expected[c] - in[c]));
    }
  }
  // Measured 4.6e-8 (float rounding); bound 1e-6, against a 0.083 change of primaries.
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(change, 0.05);

  // Another white (ACES AP1, white near D60): the file's white comes out white (relative
  // colorimetry through the Bradford adaptation).
  Image white(1, 1, 3);
  for (int c = 0; c < 3; ++c) white.at(0, 0, c) = 0.5f;
  WriteExr(dir / "ap1.exr", white,
           {0.713f, 0.293f, 0.165f, 0.830f, 0.128f, 0.044f, 0.32168f, 0.33767f});
  const Image ap1 = ReadImage(dir / "ap1.exr").image;
  // Measured 0 (exact in float); bound 1e-6.
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(ap1.at(0, 0, c), 0.5, 1e-6) << c;

  // Rec.709 chromaticities: nothing to convert.
  WriteExr(dir / "rec709.exr", image, {0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f});
  const LoadedImage plain = ReadImage(dir / "rec709.exr");
  EXPECT_EQ(plain.info.encoding.Name(), "linear");
  EXPECT_EQ(plain.image.at(5, 0, 1), image.at(5, 0, 1));
}

// The band reader (streamed fitting) decides once, when the file is opened, and converts each
// band by that decision: an Adobe RGB TIFF of 5 rows read in bands of 2, 2 and 1 rows goes
// through the profile as the whole image does, and an OpenEXR with Display P3 chromaticities
// through the same matrix.
TEST(SampleEncodingTest, BandReaderDecodesEachBandAsTheWholeImage) {
  TempDir dir;
  constexpr int kWidth = 40, kHeight = 5;
  const auto codes = NearGreyCodes(kWidth * kHeight, 16);
  ASSERT_NO_FATAL_FAILURE(WriteAdobeRgbTiff(dir / "adobe.tif", kWidth, kHeight, codes));
  Image p3_values(kWidth, kHeight, 3);
  for (int y = 0; y < kHeight; ++y) {
    for (int k = 0; k < kWidth; ++k) {
      for (int c = 0; c < 3; ++c) {
        p3_values.at(k, y, c) = 0.2f + 0.01f * static_cast<float>((k * (c + 3) + y) % 50);
      }
    }
  }
  {
    auto out = OIIO::ImageOutput::create("exr");
    OIIO::ImageSpec spec(kWidth, kHeight, 3, OIIO::TypeDesc::FLOAT);
    const std::array<float, 8> p3 = {0.680f, 0.320f, 0.265f,  0.690f,
                                     0.150f, 0.060f, 0.3127f, 0.3290f};
    spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), p3.data());
    ASSERT_TRUE(out->open((dir / "p3.exr").string(), spec));
    std::vector<float> samples;
    for (int y = 0; y < kHeight; ++y) {
      for (int k = 0; k < kWidth; ++k) {
        for (int c = 0; c < 3; ++c) samples.push_back(p3_values.at(k, y, c));
      }
    }
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, samples.data()));
    ASSERT_TRUE(out->close());
  }
  for (const char* name : {"adobe.tif", "p3.exr"}) {
    SCOPED_TRACE(name);
    const LoadedImage whole = ReadImage(dir / name);
    ImageBandReader reader(dir / name);
    EXPECT_EQ(reader.info().encoding.Name(), whole.info.encoding.Name());
    EXPECT_EQ(reader.info().encoding.decided_by, whole.info.encoding.decided_by);
    Image banded(kWidth, kHeight, 3);
    for (const int rows : {2, 2, 1}) reader.ReadNext(banded.Rows(reader.next_row(), rows));
    // Each pixel is converted alone: the bands are the whole image bit for bit (measured 0).
    for (int y = 0; y < kHeight; ++y) {
      for (int k = 0; k < kWidth; ++k) {
        for (int c = 0; c < 3; ++c) {
          ASSERT_EQ(banded.at(k, y, c), whole.image.at(k, y, c)) << k << "," << y << "," << c;
        }
      }
    }
  }
  // And the banded Adobe RGB read is the hand decoding (the whole image's bound above, 5e-5).
  ImageBandReader reader(dir / "adobe.tif");
  EXPECT_EQ(reader.info().encoding.decided_by, "icc-profile");
  Image banded(kWidth, kHeight, 3);
  for (const int rows : {3, 2}) reader.ReadNext(banded.Rows(reader.next_row(), rows));
  Image as_row(kWidth * kHeight, 1, 3);
  for (int y = 0; y < kHeight; ++y) {
    for (int k = 0; k < kWidth; ++k) {
      for (int c = 0; c < 3; ++c) as_row.at(y * kWidth + k, 0, c) = banded.at(k, y, c);
    }
  }
  EXPECT_LT(MaxAdobeError(as_row, codes, 65535.0), 5e-5);
}

TEST(SampleEncodingTest, DisagreeingImagesOfASetAreReported) {
  EXPECT_FALSE(WarnIfEncodingsDisagree(
      {{"a.png", "linear", "png-gama", ""}, {"b.png", "linear", "default", ""}}));
  EXPECT_TRUE(WarnIfEncodingsDisagree(
      {{"a.png", "linear", "png-gama", ""}, {"b.png", "srgb", "png-srgb", ""}}));
}

}  // namespace
}  // namespace photomat

// Camera RAW through OpenImageIO's LibRaw plugin (CameraRawOptions): values proportional to
// exposure. The RAW files are DNGs this test writes with libtiff from a known linear image.

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tiffio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

constexpr int kWidth = 48, kHeight = 32;

// The scene: linear values in [0.02, 0.2] that vary over the frame and between channels.
double Scene(int x, int y, int c) {
  return 0.02 + 0.12 * x / (kWidth - 1) + 0.04 * c + 0.02 * y / (kHeight - 1);
}

// A DNG 1.4 of Scene() * exposure, 16-bit, black 0, white 65535, neutral white balance. The
// colour matrix (XYZ -> camera) is the XYZ -> linear sRGB matrix, so the camera's RGB is linear
// sRGB. `bayer`: a CFA (RGGB) image of one sample per pixel (PhotometricInterpretation 32803);
// otherwise LinearRaw (34892), three samples per pixel.
void WriteDng(const fs::path& path, double exposure, bool bayer) {
  TIFF* tif = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(tif, nullptr);
  const int samples = bayer ? 1 : 3;
  TIFFSetField(tif, TIFFTAG_SUBFILETYPE, 0);
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, kWidth);
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, kHeight);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 16);
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, samples);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, bayer ? 32803 : 34892);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_NONE);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, kHeight);
  TIFFSetField(tif, TIFFTAG_ORIENTATION, 1);
  TIFFSetField(tif, TIFFTAG_MAKE, "photomat");
  TIFFSetField(tif, TIFFTAG_MODEL, "synthetic");
  const std::uint8_t version[4] = {1, 4, 0, 0}, backward[4] = {1, 1, 0, 0};
  TIFFSetField(tif, TIFFTAG_DNGVERSION, version);
  TIFFSetField(tif, TIFFTAG_DNGBACKWARDVERSION, backward);
  TIFFSetField(tif, TIFFTAG_UNIQUECAMERAMODEL, "photomat synthetic");
  const float xyz_to_camera[9] = {3.2406f, -1.5372f, -0.4986f, -0.9689f, 1.8758f,
                                  0.0415f, 0.0557f,  -0.2040f, 1.0570f};
  TIFFSetField(tif, TIFFTAG_COLORMATRIX1, 9, xyz_to_camera);
  TIFFSetField(tif, TIFFTAG_CALIBRATIONILLUMINANT1, 21);  // D65
  const float neutral[3] = {1.0f, 1.0f, 1.0f};
  TIFFSetField(tif, TIFFTAG_ASSHOTNEUTRAL, 3, neutral);
  const std::uint32_t white = 65535;
  TIFFSetField(tif, TIFFTAG_WHITELEVEL, 1, &white);
  if (bayer) {
    const std::uint16_t repeat[2] = {2, 2};
    const std::uint8_t rggb[4] = {0, 1, 1, 2};
    TIFFSetField(tif, TIFFTAG_CFAREPEATPATTERNDIM, repeat);
    TIFFSetField(tif, TIFFTAG_CFAPATTERN, 4, rggb);
  }
  std::vector<std::uint16_t> row(static_cast<std::size_t>(kWidth) * samples);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      for (int s = 0; s < samples; ++s) {
        const int c = bayer ? (y % 2) + (x % 2) : s;  // R G / G B
        row[x * samples + s] =
            static_cast<std::uint16_t>(std::lround(Scene(x, y, c) * exposure * 65535.0));
      }
    }
    ASSERT_EQ(TIFFWriteScanline(tif, row.data(), static_cast<std::uint32_t>(y), 0), 1);
  }
  TIFFClose(tif);
}

struct Proportionality {
  double worst_relative = 0.0;  // max |v_e / (e v_1) - 1|
  double worst_truth = 0.0;     // max |v_1 / Scene - 1| (interior pixels for a Bayer image)
};

Proportionality MeasureSeries(bool bayer, const std::vector<double>& exposures) {
  TempDir dir;
  std::vector<Image> images;
  for (const double e : exposures) {
    const fs::path path = dir / fmt::format("frame_{}.dng", e);
    WriteDng(path, e, bayer);
    const LoadedImage loaded = ReadImage(path);
    EXPECT_EQ(loaded.info.encoding.decided_by, "camera-raw");
    EXPECT_EQ(loaded.info.colour_space, ColourSpace::kLinear);
    images.push_back(loaded.image);
  }
  Proportionality result;
  const Image& base = images.front();
  EXPECT_EQ(base.width(), kWidth);
  EXPECT_EQ(base.channels(), 3);
  for (std::size_t i = 1; i < images.size(); ++i) {
    const double ratio = exposures[i] / exposures.front();
    for (int c = 0; c < 3; ++c) {
      for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x) {
          const double v1 = base.at(x, y, c), ve = images[i].at(x, y, c);
          result.worst_relative = std::max(result.worst_relative, std::abs(ve / (ratio * v1) - 1));
        }
      }
    }
  }
  // Against the scene: a bilinear demosaic of this smooth scene is exact away from the border,
  // except for the channel a CFA site lacks, interpolated from neighbours (the ramp is linear in
  // x and y, so the average of two neighbours is exact too).
  for (int c = 0; c < 3; ++c) {
    for (int y = 2; y < kHeight - 2; ++y) {
      for (int x = 2; x < kWidth - 2; ++x) {
        const double truth = Scene(x, y, c) * exposures.front();
        result.worst_truth = std::max(result.worst_truth, std::abs(base.at(x, y, c) / truth - 1));
      }
    }
  }
  return result;
}

TEST(CameraRawTest, LinearRawDngIsProportionalToExposure) {
  const Proportionality p = MeasureSeries(false, {1.0, 2.0, 4.0});
  // Measured 3.8e-4 (16-bit quantisation of the darkest samples: 0.5 / 1311 codes); bound 1 %
  // (the target).
  EXPECT_LT(p.worst_relative, 0.01);
  // The stored linear values come back (the colour matrix makes camera RGB linear sRGB).
  // Measured 2.6e-4; bound 1 %.
  EXPECT_LT(p.worst_truth, 0.01);
}

TEST(CameraRawTest, BayerDngWithLinearDemosaicIsProportionalToExposure) {
  const Proportionality p = MeasureSeries(true, {1.0, 2.0, 4.0});
  // Measured 6.2e-4; bound 1 %.
  EXPECT_LT(p.worst_relative, 0.01);
  // Measured 4.0e-4; bound 1 %.
  EXPECT_LT(p.worst_truth, 0.01);
}

TEST(CameraRawTest, AGivenWhiteBalanceScalesTheChannels) {
  TempDir dir;
  WriteDng(dir / "frame.dng", 1.0, false);
  const Image camera = ReadImage(dir / "frame.dng").image;
  ImageReadOptions options;
  options.camera_raw.white_balance = std::array<float, 4>{2.0f, 1.0f, 1.0f, 1.0f};
  const Image balanced = ReadImage(dir / "frame.dng", options).image;
  // LibRaw normalises the multipliers to the smallest (1), so red doubles, green and blue stay.
  const int x = kWidth / 2, y = kHeight / 2;
  EXPECT_NEAR(balanced.at(x, y, 0) / camera.at(x, y, 0), 2.0, 0.01);
  EXPECT_NEAR(balanced.at(x, y, 1) / camera.at(x, y, 1), 1.0, 0.01);
}

}  // namespace
}  // namespace photomat

#include "calibrate/radiometry/response_curve.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/colour.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

// A camera with a gamma-2.2 response photographing a scene of smoothly varying radiance.
double Camera(double exposure) { return std::pow(std::clamp(exposure, 0.0, 1.0), 1.0 / 2.2); }

std::vector<Image> ExposureSeries(const std::vector<double>& times) {
  std::vector<Image> images;
  for (double t : times) {
    Image image(64, 48, 3);
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 64; ++x) {
        const double radiance = 0.02 * std::pow(40.0, (x + 64.0 * (y % 6)) / (64.0 * 6));
        for (int c = 0; c < 3; ++c) {
          const double code = std::round(255.0 * Camera(radiance * (1.0 + 0.1 * c) * t));
          image.at(x, y, c) = static_cast<float>(code / 255.0);
        }
      }
    }
    images.push_back(std::move(image));
  }
  return images;
}

TEST(ResponseCurveTest, DebevecRecoversAGammaCurve) {
  const std::vector<double> times = {0.125, 0.25, 0.5, 1.0, 2.0, 4.0};
  const ResponseCurve curve = RecoverResponseDebevec(ExposureSeries(times), times);
  ASSERT_EQ(curve.levels(), 256);
  // Up to scale, the curve is code^2.2: compare the ratios of mid codes to code 200.
  for (int channel = 0; channel < 3; ++channel) {
    for (int code : {40, 80, 120, 160, 220}) {
      const double expected = std::pow(code / 200.0, 2.2);
      const double recovered = curve.table(channel)[code] / curve.table(channel)[200];
      EXPECT_NEAR(recovered / expected, 1.0, 0.06) << "channel " << channel << " code " << code;
    }
  }
  // Linearised, one exposure is twice the one before (on unclipped, well-exposed pixels).
  const auto series = ExposureSeries(times);
  const Image a = curve.Linearise(series[2]), b = curve.Linearise(series[3]);
  int compared = 0;
  for (std::size_t p = 0; p < a.pixel_count(); ++p) {
    if (b.pixel(p)[1] > 0.95f || series[2].pixel(p)[1] < 0.15f) continue;
    EXPECT_NEAR(b.pixel(p)[1] / a.pixel(p)[1], 2.0, 0.2);
    ++compared;
  }
  EXPECT_GT(compared, 500);
}

TEST(ResponseCurveTest, SrgbCurveMatchesTheDecoder) {
  const ResponseCurve srgb = ResponseCurve::Srgb();
  EXPECT_NEAR(srgb.ToLinear(0, 128 / 255.0), SrgbToLinear(128 / 255.0), 1e-12);
  EXPECT_NEAR(srgb.ToLinear(0, 0.5), SrgbToLinear(0.5), 1e-4);  // between codes: interpolated
  EXPECT_DOUBLE_EQ(ResponseCurve::Identity().ToLinear(2, 0.3), 0.3);
}

TEST(ResponseCurveTest, FileRoundTripAndBadInput) {
  testing::TempDir dir;
  WriteResponseCurve(dir / "response.json", ResponseCurve::Srgb());
  const ResponseCurve read = ReadResponseCurve(dir / "response.json");
  EXPECT_EQ(read.source(), "srgb");
  EXPECT_DOUBLE_EQ(read.table(1)[77], ResponseCurve::Srgb().table(1)[77]);
  testing::WriteFile(
      dir / "bad.json",
      R"({"format": "photomat-response", "version": 1, "channels": [[0, 0.5, 0.4]]})");
  try {
    ReadResponseCurve(dir / "bad.json");
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("bad.json"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("non-decreasing"), std::string::npos);
  }
  EXPECT_THROW(RecoverResponseDebevec({Image(4, 4, 3)}, {1.0}), Error);
  EXPECT_THROW(RecoverResponseDebevec({Image(4, 4, 3), Image(4, 4, 3)}, {1.0, -1.0}), Error);
  EXPECT_THROW(ResponseCurve::Srgb(3).Linearise(Image(2, 2, 2)), Error);
}

}  // namespace
}  // namespace photomat

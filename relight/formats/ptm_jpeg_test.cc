#include "relight/formats/ptm_jpeg.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.h"
#include "relight/formats/ptm_jpeg_test_codings.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

constexpr int kWidth = 24;
constexpr int kHeight = 16;

// Nine smooth planes correlated as PTM planes are: a0 and a1 fall where a5 rises (so inverted
// references predict them), R and B follow G, plus each plane's own detail.
std::vector<PlaneBytes> CorrelatedPlanes() {
  std::vector<PlaneBytes> planes(9, PlaneBytes(kWidth * kHeight));
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const double shape = 60.0 * std::sin(0.25 * x) * std::cos(0.3 * y) + 2.0 * x;
      const double detail[9] = {3 * std::cos(0.5 * y), 4 * std::sin(0.4 * x),
                                0.5 * x + y,           2 * std::sin(0.2 * x * y),
                                30 + 3.0 * y,          0,
                                5 * std::cos(0.7 * x), 0,
                                4 * std::sin(0.6 * y)};
      const double value[9] = {250 - (128 + shape) + detail[0],
                               250 - (125 + shape) + detail[1],
                               90 + detail[2],
                               128 + detail[3],
                               detail[4],
                               125 + shape,
                               0.9 * (120 + shape) + detail[6],
                               120 + shape,
                               0.8 * (120 + shape) + 20 + detail[8]};
      for (int s = 0; s < 9; ++s) {
        planes[s][y * kWidth + x] =
            static_cast<std::uint8_t>(std::clamp(std::lround(value[s]), 0L, 255L));
      }
    }
  }
  return planes;
}

std::vector<PlaneBytes> RoundTrip(const PtmJpegCoding& coding,
                                  const std::vector<PlaneBytes>& planes) {
  const std::vector<EncodedPtmPlane> encoded = EncodePtmJpegPlanes(coding, planes, kWidth, kHeight);
  std::vector<PtmJpegStream> streams;
  const auto bytes = [](const std::string& s) {
    return std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
  };
  for (const EncodedPtmPlane& plane : encoded) {
    streams.push_back({bytes(plane.jpeg), bytes(plane.side_information)});
  }
  return DecodePtmJpegPlanes(coding, streams, kWidth, kHeight, "t.ptm");
}

int WorstError(const std::vector<PlaneBytes>& a, const std::vector<PlaneBytes>& b) {
  int worst = 0;
  for (std::size_t s = 0; s < a.size(); ++s) {
    for (std::size_t p = 0; p < a[s].size(); ++p) {
      worst = std::max(worst, std::abs(a[s][p] - b[s][p]));
    }
  }
  return worst;
}

TEST(PtmJpegTest, PredictionInvertsAndShiftsTheReference) {
  // A 4 x 3 reference, r(x, y) = 10 y + x + 1 (y over the stored rows).
  PlaneBytes reference(12);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 4; ++x) reference[y * 4 + x] = static_cast<std::uint8_t>(10 * y + x + 1);
  }
  PtmPlaneCoding plane;
  plane.motion_x = 1;
  plane.motion_y = -1;
  // Not motion compensated: the vector is ignored (as RTIViewer does), plain copy.
  EXPECT_EQ(PredictPtmPlane(reference, plane, 4, 3), reference);
  plane.inverted = true;
  plane.motion_compensated = true;
  const PlaneBytes prediction = PredictPtmPlane(reference, plane, 4, 3);
  // (x, y) takes 255 - r(x + 1, y - 1), the edge pixel beyond the image.
  EXPECT_EQ(prediction[0 * 4 + 0], 255 - 2);   // r(1, 0): row -1 clamps to 0
  EXPECT_EQ(prediction[1 * 4 + 2], 255 - 4);   // r(3, 0)
  EXPECT_EQ(prediction[2 * 4 + 0], 255 - 12);  // r(1, 1)
  EXPECT_EQ(prediction[2 * 4 + 3], 255 - 14);  // r(3, 1): column 4 clamps to 3
  EXPECT_EQ(plane.Transform(), 3);
}

// Must show: the example's prediction graph encodes and decodes as accurately as independent
// planes (closed loop: a chain of two references, a5 -> a0, adds no error), and the prediction
// is what makes the residuals cheap.
TEST(PtmJpegTest, PredictedPlanesRoundTripWithinTheJpegQuantisation) {
  const std::vector<PlaneBytes> planes = CorrelatedPlanes();
  for (int quality : {75, 95}) {
    const PtmJpegCoding predicted = testing::ExampleLrgbCoding(quality);
    const PtmJpegCoding independent = PtmJpegCoding::Unpredicted(9, quality);
    const int predicted_error = WorstError(RoundTrip(predicted, planes), planes);
    const int independent_error = WorstError(RoundTrip(independent, planes), planes);
    // Measured worst errors: quality 75: 6 predicted, 6 independent; 95: 5 and 5. Bounds: the
    // independent planes' error + 2 codes (a residual is coded as coarsely as a plane, and the
    // closed loop keeps the reference's error out of it), and the measured error x 1.5.
    EXPECT_LE(predicted_error, independent_error + 2) << quality;
    EXPECT_LE(predicted_error, quality == 75 ? 9 : 8) << quality;
    std::size_t predicted_bytes = 0, independent_bytes = 0;
    for (const auto& plane : EncodePtmJpegPlanes(predicted, planes, kWidth, kHeight)) {
      predicted_bytes += plane.jpeg.size();
    }
    for (const auto& plane : EncodePtmJpegPlanes(independent, planes, kWidth, kHeight)) {
      independent_bytes += plane.jpeg.size();
    }
    EXPECT_LT(predicted_bytes, independent_bytes) << quality;
    ::testing::Test::RecordProperty(
        fmt::format("quality_{}", quality),
        fmt::format("worst error predicted {} independent {}; bytes {} vs {}", predicted_error,
                    independent_error, predicted_bytes, independent_bytes));
  }
}

// Must show: where the prediction misses by about +-128 the residual wraps modulo 256, a mild
// texture of the plane becomes a full-range one in the JPEG, and the JPEG's smoothing of it is
// far off; with a tolerance every such pixel is sent and the plane is within it.
TEST(PtmJpegTest, SideInformationCarriesWhatTheJpegCannot) {
  std::vector<PlaneBytes> planes(2, PlaneBytes(kWidth * kHeight, 10));
  std::mt19937 random(17);
  for (int p = 0; p < kWidth * kHeight; ++p) {
    // 133 or 143 at random: residuals 251 or 5 against plane 0's 10.
    planes[1][p] = static_cast<std::uint8_t>(random() % 2 == 0 ? 133 : 143);
  }
  PtmJpegCoding coding = PtmJpegCoding::Unpredicted(2, 50);
  coding.planes[1].reference = 0;
  coding.planes[1].order = 1;
  const int without = WorstError(RoundTrip(coding, planes), planes);
  coding.side_information_tolerance = 6;
  const int with = WorstError(RoundTrip(coding, planes), planes);
  const auto side = EncodePtmJpegPlanes(coding, planes, kWidth, kHeight)[1].side_information;
  EXPECT_GE(without, 40);  // measured 57 (bound 57 x 0.7): the wrapped residuals' JPEG error
  EXPECT_LE(with, 6);
  EXPECT_FALSE(side.empty());
  EXPECT_EQ(side.size() % 5, 0u);
  ::testing::Test::RecordProperty("worst_error", fmt::format("{} without, {} with ({} records)",
                                                             without, with, side.size() / 5));
}

TEST(PtmJpegTest, CodingFaultsNameTheField) {
  const auto fails = [](const PtmJpegCoding& coding, const std::string& message) {
    EXPECT_THAT([&] { CheckPtmJpegCoding(coding, 9, kWidth, kHeight, "bad.ptm"); },
                ThrowsMessage<Error>(::testing::AllOf(HasSubstr("bad.ptm: "), HasSubstr(message))))
        << message;
  };
  EXPECT_NO_THROW(
      CheckPtmJpegCoding(testing::ExampleLrgbCoding(90), 9, kWidth, kHeight, "good.ptm"));
  PtmJpegCoding coding = testing::ExampleLrgbCoding(90);
  coding.planes[1].reference = 0;  // 0 -> 5 -> 1 -> 0
  fails(coding, "the JPEG reference planes form a cycle: 0 -> 5 -> 1 -> 0");
  coding = testing::ExampleLrgbCoding(90);
  coding.planes[3].reference = 3;
  fails(coding, "JPEG plane 3: invalid reference plane 3");
  coding.planes[3].reference = 9;
  fails(coding, "JPEG plane 3: invalid reference plane 9");
  coding.planes[3].reference = -2;
  fails(coding, "JPEG plane 3: invalid reference plane -2");
  coding = testing::ExampleLrgbCoding(90);
  coding.planes[4].order = 3;  // twice
  fails(coding, "decoding order is not a permutation of the 9 planes");
  coding.planes[4].order = 9;
  fails(coding, "(plane 4 has order 9)");
  coding = testing::ExampleLrgbCoding(90);
  std::swap(coding.planes[1].order, coding.planes[5].order);  // a5 before its reference a1
  fails(coding, "JPEG plane 5 refers to plane 1, which is decoded after it");
  coding = testing::ExampleLrgbCoding(90);
  coding.planes[6].motion_compensated = true;
  coding.planes[6].motion_x = kWidth;
  fails(coding, "JPEG plane 6: motion vector (24, 0) is not shorter than the 24 x 16 image");
  coding.planes[6].motion_x = 0;
  coding.planes[6].motion_y = -kHeight;
  fails(coding, "motion vector (0, -16)");
  coding.planes.pop_back();
  fails(coding, "the JPEG coding describes 8 planes, the format has 9");
  // The writer checks the same and names no file.
  EXPECT_THAT([&] { EncodePtmJpegPlanes(coding, CorrelatedPlanes(), kWidth, kHeight); },
              ThrowsMessage<Error>(HasSubstr("describes 8 planes")));
}

}  // namespace
}  // namespace photomat

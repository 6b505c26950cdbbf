#include "synthesize/solid/solid_quality.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace photomat {
namespace {

// A one-channel 4 x 4 x 4 volume whose voxel i holds value(i).
template <typename Value>
Image Ramp(Value value) {
  Image volume(ImageExtent::Cube(4), 1);
  for (std::size_t i = 0; i < volume.pixel_count(); ++i) {
    volume.pixel(i)[0] = static_cast<float>(value(static_cast<double>(i)));
  }
  return volume;
}

TEST(SolidQualityTest, EarthMoverDistanceIsTheMeanShiftInUnitsOfTheRange) {
  const Image reference = Ramp([](double i) { return i / 63.0; });  // range 1
  EXPECT_DOUBLE_EQ(EarthMoverDistance(reference, reference), 0.0);
  // Every value moved by 0.1: the distributions are 0.1 apart everywhere.
  EXPECT_NEAR(EarthMoverDistance(Ramp([](double i) { return i / 63.0 + 0.1; }), reference), 0.1,
              1e-6);
  // The order of the voxels does not matter, only their values.
  EXPECT_NEAR(EarthMoverDistance(Ramp([](double i) { return (63.0 - i) / 63.0; }), reference), 0.0,
              1e-9);
  // Half the voxels at 0 and half at 2 (range 2) against all at 0: half the mass moves by 2.
  const Image split = Ramp([](double i) { return i < 32 ? 0.0 : 2.0; });
  EXPECT_NEAR(EarthMoverDistance(Ramp([](double) { return 0.0; }), split), 0.5, 1e-9);
  // Volumes of different sizes compare their distributions.
  Image large(ImageExtent::Cube(8), 1);
  for (std::size_t i = 0; i < large.pixel_count(); ++i) large.pixel(i)[0] = i % 2 ? 2.0f : 0.0f;
  EXPECT_NEAR(EarthMoverDistance(large, split), 0.0, 1e-9);
  EXPECT_THROW(EarthMoverDistance(Image(ImageExtent::Cube(4), 3), reference), Error);
}

TEST(SolidQualityTest, HistogramDistanceCountsTheMassInOtherBins) {
  const Image split = Ramp([](double i) { return i < 32 ? 0.0 : 2.0; });
  EXPECT_DOUBLE_EQ(HistogramDistance(split, split), 0.0);
  // All in the first bin against half in the first and half in the last: L1 = 0.5 + 0.5.
  EXPECT_DOUBLE_EQ(HistogramDistance(Ramp([](double) { return 0.0; }), split), 1.0);
  // A shift within a bin is invisible to the histogram, not to the earth mover's distance.
  const Image nudged = Ramp([](double i) { return i < 32 ? 0.01 : 2.0; });
  EXPECT_DOUBLE_EQ(HistogramDistance(nudged, split, 32), 0.0);
  EXPECT_NEAR(EarthMoverDistance(nudged, split), 0.5 * 0.01 / 2.0, 1e-9);
}

}  // namespace
}  // namespace photomat

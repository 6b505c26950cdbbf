#include "synthesize/texture/matching_space.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/random.h"

namespace photomat {
namespace {

// Three channels on very different scales (as Gradient's normals and albedo), one constant.
Image ThreeScales() {
  Image image(8, 6, 4);
  Random random(3);
  for (std::size_t i = 0; i < image.pixel_count(); ++i) {
    image.pixel(i)[0] = static_cast<float>(random.Uniform(-0.01, 0.02));
    image.pixel(i)[1] = static_cast<float>(random.Uniform(100.0, 400.0));
    image.pixel(i)[2] = static_cast<float>(random.Normal());
    image.pixel(i)[3] = 5.0f;
  }
  return image;
}

TEST(MatchingSpaceTest, MinMaxGivesEveryChannelUnitRange) {
  const Image space = ChannelTransform::Fit(ThreeScales(), {}).Apply(ThreeScales());
  for (int c = 0; c < 3; ++c) {
    const auto plane = space.plane(c);
    const auto [low, high] = std::minmax_element(plane.begin(), plane.end());
    EXPECT_NEAR(*high - *low, 1.0, 1e-5) << c;
    double mean = 0.0;
    for (float v : plane) mean += v;
    EXPECT_NEAR(mean / plane.size(), 0.0, 1e-5) << "centred: " << c;
  }
  // A constant channel cannot guide matching.
  for (float v : space.plane(3)) EXPECT_EQ(v, 0.0f);
}

TEST(MatchingSpaceTest, ZScoreGivesUnitStandardDeviation) {
  MatchingOptions options;
  options.scaling = ChannelScaling::kZScore;
  const Image space = ChannelTransform::Fit(ThreeScales(), options).Apply(ThreeScales());
  for (int c = 0; c < 3; ++c) {
    double sum2 = 0.0;
    for (float v : space.plane(c)) sum2 += v * v;
    EXPECT_NEAR(std::sqrt(sum2 / space.pixel_count()), 1.0, 1e-4) << c;
  }
}

TEST(MatchingSpaceTest, WeightsMultiplyEachChannelsErrorTerm) {
  const Image image = ThreeScales();
  for (ErrorMetric metric : {ErrorMetric::kSsd, ErrorMetric::kSad}) {
    MatchingOptions plain, weighted;
    plain.metric = weighted.metric = metric;
    weighted.weights = {4.0, 0.0, 0.5, 1.0};
    const Image a = ChannelTransform::Fit(image, plain).Apply(image);
    const Image b = ChannelTransform::Fit(image, weighted).Apply(image);
    for (int c = 0; c < 3; ++c) {
      const double plain_error = PairError(metric, a.at(0, 0, c), a.at(5, 4, c));
      const double weighted_error = PairError(metric, b.at(0, 0, c), b.at(5, 4, c));
      EXPECT_NEAR(weighted_error, weighted.weights[c] * plain_error, 1e-5 * (1 + plain_error))
          << ToString(metric) << " channel " << c;
    }
  }
}

TEST(MatchingSpaceTest, RejectsBadWeightsAndNames) {
  const Image image = ThreeScales();
  MatchingOptions options;
  options.weights = {1.0, 2.0};
  EXPECT_THROW(ChannelTransform::Fit(image, options), Error);
  options.weights = {1.0, -1.0, 1.0, 1.0};
  EXPECT_THROW(ChannelTransform::Fit(image, options), Error);
  options.weights = {1.0, NAN, 1.0, 1.0};
  EXPECT_THROW(ChannelTransform::Fit(image, options), Error);
  EXPECT_EQ(ParseErrorMetric("sad"), ErrorMetric::kSad);
  EXPECT_EQ(ParseChannelScaling("zscore"), ChannelScaling::kZScore);
  EXPECT_THROW(ParseErrorMetric("l3"), Error);
  EXPECT_THROW(ParseChannelScaling("none"), Error);
}

}  // namespace
}  // namespace photomat

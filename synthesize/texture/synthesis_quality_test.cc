#include "synthesize/texture/synthesis_quality.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "core/error.h"
#include "core/random.h"

namespace photomat {
namespace {

// Channel 0 in [0, 1], channel 1 in [0, 10]: the measures must see both alike.
Image TwoScales(int width, int height, std::uint64_t seed) {
  Image image(width, height, 2);
  Random random(seed);
  for (std::size_t i = 0; i < image.pixel_count(); ++i) {
    image.pixel(i)[0] = static_cast<float>(random.Uniform());
    image.pixel(i)[1] = static_cast<float>(10.0 * random.Uniform());
  }
  // Pin each channel's range exactly.
  image.pixel(0)[0] = 0.0f, image.pixel(1)[0] = 1.0f;
  image.pixel(0)[1] = 0.0f, image.pixel(1)[1] = 10.0f;
  return image;
}

Image Crop(const Image& image, int x0, int y0, int width, int height) {
  Image out(width, height, image.channels());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < image.channels(); ++c) out.at(x, y, c) = image.at(x0 + x, y0 + y, c);
    }
  }
  return out;
}

// The nearest-patch distance by trying every pair in double.
double NearestPatchDistanceByEnumeration(const Image& sample, const Image& output, int patch,
                                         int stride) {
  const double scale[2] = {1.0, 0.1};
  double total = 0.0;
  int count = 0;
  for (int oy = 0; oy + patch <= output.height(); oy += stride) {
    for (int ox = 0; ox + patch <= output.width(); ox += stride) {
      double best = std::numeric_limits<double>::infinity();
      for (int sy = 0; sy + patch <= sample.height(); ++sy) {
        for (int sx = 0; sx + patch <= sample.width(); ++sx) {
          double sum = 0.0;
          for (int v = 0; v < patch; ++v) {
            for (int u = 0; u < patch; ++u) {
              for (int c = 0; c < 2; ++c) {
                const double d = scale[c] * (static_cast<double>(output.at(ox + u, oy + v, c)) -
                                             sample.at(sx + u, sy + v, c));
                sum += d * d;
              }
            }
          }
          best = std::min(best, sum);
        }
      }
      total += std::sqrt(best / (patch * patch * 2));
      ++count;
    }
  }
  return total / count;
}

TEST(SynthesisQualityTest, CopiedPatchesAreAtDistanceZero) {
  const Image sample = TwoScales(20, 18, 1);
  EXPECT_EQ(MeanNearestPatchDistance(sample, Crop(sample, 3, 5, 14, 12), {5, 3}), 0.0);
}

TEST(SynthesisQualityTest, NearestPatchDistanceMatchesEnumeration) {
  const Image sample = TwoScales(16, 14, 2);
  const Image output = TwoScales(15, 13, 3);
  for (int stride : {2, 5}) {
    QualityOptions options;
    options.patch_size = 4;
    options.patch_stride = stride;
    EXPECT_NEAR(MeanNearestPatchDistance(sample, output, options),
                NearestPatchDistanceByEnumeration(sample, output, 4, stride), 1e-6);
  }
}

TEST(SynthesisQualityTest, NoiseShowsAsItsRmsInNormalisedUnits) {
  const Image sample = TwoScales(40, 40, 4);
  Image noisy = sample;
  Random random(5);
  const double sigma = 0.01;
  for (std::size_t i = 0; i < noisy.pixel_count(); ++i) {
    noisy.pixel(i)[0] += static_cast<float>(sigma * random.Normal());
    noisy.pixel(i)[1] += static_cast<float>(10.0 * sigma * random.Normal());
  }
  // The nearest patch can be a little closer than the true one, never farther.
  const double distance = MeanNearestPatchDistance(sample, noisy);
  EXPECT_LT(distance, 1.05 * sigma);
  EXPECT_GT(distance, 0.8 * sigma);
  EXPECT_THROW(MeanNearestPatchDistance(sample, Image(40, 40, 3)), Error);
  EXPECT_THROW(MeanNearestPatchDistance(sample, Image(5, 40, 2)), Error);
}

// Coverage counts each sample pixel once, however often it is copied: a 12 x 10 output of two
// 6 x 10 pieces of a 30 x 10 sample covers 120 of its 300 pixels; copying the first piece twice
// covers 60; the measure is in MeasureSynthesis only with a map.
TEST(SynthesisQualityTest, SampleCoverageIsTheShareOfSamplePixelsCopied) {
  SourceMap two_pieces(12, 10, 30, 10), one_piece_twice(12, 10, 30, 10);
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 12; ++x) {
      two_pieces.Set(x, y, {x < 6 ? x : x + 10, y});
      one_piece_twice.Set(x, y, {x % 6, y});
    }
  }
  EXPECT_DOUBLE_EQ(SampleCoverage(two_pieces), 120.0 / 300.0);
  EXPECT_DOUBLE_EQ(SampleCoverage(one_piece_twice), 60.0 / 300.0);
  Image sample(30, 10, 1);
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 30; ++x) sample.at(x, y, 0) = static_cast<float>(x + y);
  }
  const Image out = two_pieces.Apply(sample);
  EXPECT_FALSE(MeasureSynthesis(sample, out).sample_coverage.has_value());
  EXPECT_DOUBLE_EQ(MeasureSynthesis(sample, out, &two_pieces).sample_coverage.value(), 0.4);
}

TEST(SynthesisQualityTest, SeamScoreComparesSeamsWithInsidePairs) {
  // A ramp sample; the output joins two pieces of it side by side.
  Image sample(30, 10, 1);
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 30; ++x) sample.at(x, y, 0) = static_cast<float>(x);
  }
  SourceMap map(12, 10, 30, 10);
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 12; ++x) map.Set(x, y, {x < 6 ? x : x + 10, y});
  }
  const Image out = map.Apply(sample);
  const ChannelTransform scale = ChannelTransform::Fit(sample, {});
  const PairContrast seams = SeamScore(out, map, scale);
  EXPECT_EQ(seams.pairs, 10u);  // the column pair 5 | 6 in every row
  EXPECT_EQ(seams.reference_pairs, 11u * 10u + 12u * 9u - 10u);
  const double step = 1.0 / 29.0;                      // one pixel of the ramp, normalised
  EXPECT_NEAR(seams.mean, 121.0 * step * step, 1e-6);  // a jump of 11 pixels
  EXPECT_NEAR(seams.reference_mean, (10.0 * 10.0 * step * step) / 208.0, 1e-6);
  EXPECT_NEAR(seams.ratio, seams.mean / seams.reference_mean, 1e-12);
  EXPECT_THROW(SeamScore(Crop(out, 0, 0, 11, 10), map, scale), Error);
}

TEST(SynthesisQualityTest, WrapScoreSeesPeriodicImagesAsSeamless) {
  // A checkerboard of even size: every pair, inside or across the wrap, differs by one.
  Image checkerboard(24, 16, 1), ramp(24, 16, 1);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 24; ++x) {
      checkerboard.at(x, y, 0) = static_cast<float>((x + y) % 2);
      ramp.at(x, y, 0) = static_cast<float>(x + y);
    }
  }
  const PairContrast wrap = WrapScore(checkerboard, ChannelTransform::Fit(checkerboard, {}));
  EXPECT_EQ(wrap.pairs, 24u + 16u);
  EXPECT_EQ(wrap.reference_pairs, 23u * 16u + 24u * 15u);
  EXPECT_DOUBLE_EQ(wrap.ratio, 1.0);
  // A ramp jumps by 23 across the wrap, by 1 inside.
  EXPECT_NEAR(WrapScore(ramp, ChannelTransform::Fit(ramp, {})).ratio,
              (16 * 529.0 + 24 * 225.0) / 40.0, 1e-3);
}

TEST(SynthesisQualityTest, RoughnessIsOneForTheSampleAndBelowForABlur) {
  const Image sample = TwoScales(30, 30, 6);
  const ChannelTransform scale = ChannelTransform::Fit(sample, {});
  EXPECT_NEAR(RoughnessRatio(sample, sample, scale).ratio, 1.0, 1e-12);
  Image blurred = sample;
  for (int y = 0; y < 30; ++y) {
    for (int x = 1; x + 1 < 30; ++x) {
      for (int c = 0; c < 2; ++c) {
        blurred.at(x, y, c) =
            (sample.at(x - 1, y, c) + sample.at(x, y, c) + sample.at(x + 1, y, c)) / 3.0f;
      }
    }
  }
  EXPECT_LT(RoughnessRatio(sample, blurred, scale).ratio, 0.7);
}

TEST(SynthesisQualityTest, MeasuresAllAndWritesJson) {
  const Image sample = TwoScales(20, 20, 7);
  SourceMap map(12, 12, 20, 20);
  for (int y = 0; y < 12; ++y) {
    for (int x = 0; x < 12; ++x) map.Set(x, y, {x + 2, y + 3});
  }
  const SynthesisQuality quality = MeasureSynthesis(sample, map.Apply(sample), &map);
  EXPECT_EQ(quality.nearest_patch_distance, 0.0);
  ASSERT_TRUE(quality.seams.has_value());
  EXPECT_EQ(quality.seams->pairs, 0u);  // one verbatim piece
  const nlohmann::json json = ToJson(quality);
  EXPECT_EQ(json["patch_size"], 7);
  EXPECT_TRUE(json.contains("wrap"));
  EXPECT_TRUE(json.contains("seams"));
  EXPECT_FALSE(ToJson(MeasureSynthesis(sample, map.Apply(sample))).contains("seams"));
}

}  // namespace
}  // namespace photomat

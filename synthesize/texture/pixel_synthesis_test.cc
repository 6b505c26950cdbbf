#include "synthesize/texture/pixel_synthesis.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <map>
#include <vector>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "core/random.h"
#include "synthesize/texture/synthesis_quality.h"

namespace photomat {
namespace {

Image RandomMaps(int width, int height, int channels, std::uint64_t seed) {
  Image image(width, height, channels);
  Random random(seed);
  for (float& v : image.values()) v = static_cast<float>(random.Uniform());
  return image;
}

Image BumpsAlbedoAndNormals(int size) {
  SyntheticMaterialOptions options;
  options.pattern = SurfacePattern::kBumps;
  options.width = options.height = size;
  const SyntheticMaterial material = MakeSyntheticMaterial(options);
  Image maps(size, size, 4);
  for (std::size_t i = 0; i < maps.pixel_count(); ++i) {
    for (int c = 0; c < 3; ++c) maps.pixel(i)[c] = material.albedo.pixel(i)[c];
    maps.pixel(i)[3] = material.normals.pixel(i)[0];
  }
  return maps;
}

// A doubly periodic lattice (periods 6 and 5, sheared) in two channels: every neighbourhood of
// it recurs, so a synthesis that matches neighbourhoods can continue it without visible seams.
Image Lattice(int width, int height) {
  Image image(width, height, 2);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at(x, y, 0) = static_cast<float>((x + 2 * y) % 6) / 6.0f;
      image.at(x, y, 1) = static_cast<float>((3 * x + y) % 5) / 5.0f;
    }
  }
  return image;
}

PixelSynthesisOptions Small() {
  PixelSynthesisOptions options;
  options.levels = 1;
  return options;
}

TEST(PixelSynthesisTest, EveryOutputVectorIsASamplePixel) {
  const Image sample = RandomMaps(24, 20, 5, 1);
  std::map<std::vector<float>, SamplePixel> pixels;
  for (int y = 0; y < sample.height(); ++y) {
    for (int x = 0; x < sample.width(); ++x) {
      const auto p = sample.pixel(x, y);
      pixels[{p.begin(), p.end()}] = {x, y};
    }
  }
  const SourceMap map = PlanPixelSynthesis(sample, {40, 30, false, 2}, Small());
  ASSERT_TRUE(map.Complete());
  const Image out = map.Apply(sample);
  for (int y = 0; y < out.height(); ++y) {
    for (int x = 0; x < out.width(); ++x) {
      const auto p = out.pixel(x, y);
      const auto found = pixels.find({p.begin(), p.end()});
      ASSERT_NE(found, pixels.end()) << x << "," << y;
      EXPECT_EQ(found->second, map.at(x, y));
    }
  }
}

TEST(PixelSynthesisTest, SameSeedSameOutputOnAnyNumberOfThreads) {
  const Image sample = BumpsAlbedoAndNormals(32);
  const SynthesisTarget target{40, 36, false, 8};
  const SourceMap reference = PlanPixelSynthesis(sample, target, Small());
  EXPECT_EQ(PlanPixelSynthesis(sample, target, Small()), reference);
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    EXPECT_EQ(PlanPixelSynthesis(sample, target, Small()), reference);
  }
  SynthesisTarget other = target;
  other.seed = 9;
  EXPECT_NE(PlanPixelSynthesis(sample, other, Small()), reference);
}

TEST(PixelSynthesisTest, PrunedSearchFindsTheExhaustiveSearchsPixels) {
  const Image sample = BumpsAlbedoAndNormals(40);
  for (bool tileable : {false, true}) {
    PixelSynthesisOptions options;
    options.forced_search_rate = 0.8;
    options.search = SearchMode::kBruteForce;
    const SourceMap brute = PlanPixelSynthesis(sample, {44, 36, tileable, 6}, options);
    options.search = SearchMode::kFast;
    EXPECT_EQ(PlanPixelSynthesis(sample, {44, 36, tileable, 6}, options), brute) << tileable;
  }
}

TEST(PixelSynthesisTest, ContinuesARecurringTextureWithoutVisibleSeams) {
  const Image sample = Lattice(30, 30);
  for (double rate : {1.0, 0.5}) {
    PixelSynthesisOptions options = Small();
    options.forced_search_rate = rate;
    const SourceMap map = PlanPixelSynthesis(sample, {48, 40, false, 3}, options);
    const Image out = map.Apply(sample);
    // Wherever the source jumps, the values still follow the lattice's own neighbour rule.
    int broken = 0;
    for (int y = 0; y < out.height(); ++y) {
      for (int x = 0; x + 1 < out.width(); ++x) {
        const float a = out.at(x, y, 0) * 6.0f, b = out.at(x + 1, y, 0) * 6.0f;
        broken += std::lround(b - a + 6.0f) % 6 != 1;
      }
    }
    EXPECT_LT(broken, out.width() * out.height() / 50) << "rate " << rate;
    const PairContrast seams = SeamScore(out, map, ChannelTransform::Fit(sample, {}));
    EXPECT_GT(seams.pairs, 0u) << "the output is not one verbatim copy";
  }
}

TEST(PixelSynthesisTest, TheForcedSearchRateControlsTheContinuation) {
  const Image sample = BumpsAlbedoAndNormals(32);
  auto continued = [&](double rate) {
    PixelSynthesisOptions options = Small();
    options.forced_search_rate = rate;
    const SourceMap map = PlanPixelSynthesis(sample, {48, 32, false, 5}, options);
    int count = 0;
    for (int y = 0; y < map.height(); ++y) {
      for (int x = 0; x + 1 < map.width(); ++x) {
        count += map.at(x + 1, y).x == map.at(x, y).x + 1 && map.at(x + 1, y).y == map.at(x, y).y;
      }
    }
    return static_cast<double>(count) / (map.height() * (map.width() - 1));
  };
  const double never = continued(0.0), half = continued(0.5);
  EXPECT_GT(never, 0.9);  // only the sample's edge stops a continuation
  EXPECT_LT(half, never);
}

TEST(PixelSynthesisTest, TileableOutputWrapsLikeItsInside) {
  const Image sample = BumpsAlbedoAndNormals(48);
  const ChannelTransform scale = ChannelTransform::Fit(sample, {});
  PixelSynthesisOptions options;
  for (std::uint64_t seed : {1, 2}) {
    const Image tiled = PlanPixelSynthesis(sample, {48, 48, true, seed}, options).Apply(sample);
    const Image plain = PlanPixelSynthesis(sample, {48, 48, false, seed}, options).Apply(sample);
    EXPECT_GT(WrapScore(tiled, scale).ratio, 0.5) << seed;
    EXPECT_LT(WrapScore(tiled, scale).ratio, 1.5) << seed;
    EXPECT_GT(WrapScore(plain, scale).ratio, 3.0) << seed;
  }
}

TEST(PixelSynthesisTest, RejectsParametersOutOfRange) {
  const Image sample = RandomMaps(24, 24, 2, 1);
  const SynthesisTarget target{30, 30, false, 1};
  PixelSynthesisOptions options = Small();
  options.neighbourhood = 4;
  EXPECT_THROW(PlanPixelSynthesis(sample, target, options), Error);
  options = Small();
  options.levels = 4;  // a 3x3 coarsest level cannot hold a 5x5 neighbourhood
  EXPECT_THROW(PlanPixelSynthesis(sample, target, options), Error);
  options = Small();
  options.forced_search_rate = -0.5;
  EXPECT_THROW(PlanPixelSynthesis(sample, target, options), Error);
  EXPECT_THROW(PlanPixelSynthesis(sample, {0, 4, false, 1}, Small()), Error);
}

}  // namespace
}  // namespace photomat

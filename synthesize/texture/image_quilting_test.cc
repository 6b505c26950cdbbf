#include "synthesize/texture/image_quilting.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <map>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "core/random.h"
#include "synthesize/texture/synthesis_quality.h"

namespace photomat {
namespace {

// Six maps of a procedural material (normal x, y, z and albedo r, g, b), periodic.
Image MaterialMaps(SurfacePattern pattern, int size, std::uint64_t seed = 1) {
  SyntheticMaterialOptions options;
  options.pattern = pattern;
  options.width = options.height = size;
  options.seed = seed;
  const SyntheticMaterial material = MakeSyntheticMaterial(options);
  Image maps(size, size, 6);
  for (std::size_t i = 0; i < maps.pixel_count(); ++i) {
    for (int c = 0; c < 3; ++c) {
      maps.pixel(i)[c] = material.normals.pixel(i)[c];
      maps.pixel(i)[3 + c] = material.albedo.pixel(i)[c];
    }
  }
  return maps;
}

Image RandomMaps(int width, int height, int channels, std::uint64_t seed) {
  Image image(width, height, channels);
  Random random(seed);
  for (float& v : image.values()) v = static_cast<float>(random.Uniform(-3.0, 5.0));
  return image;
}

QuiltOptions SmallBlocks() {
  QuiltOptions options;
  options.block_size = 12;
  options.overlap = 3;
  return options;
}

TEST(ImageQuiltingTest, EveryOutputVectorIsASamplePixel) {
  const Image sample = RandomMaps(40, 36, 6, 1);
  std::map<std::vector<float>, SamplePixel> pixels;
  for (int y = 0; y < sample.height(); ++y) {
    for (int x = 0; x < sample.width(); ++x) {
      const auto p = sample.pixel(x, y);
      pixels[{p.begin(), p.end()}] = {x, y};
    }
  }
  for (bool tileable : {false, true}) {
    const BlockPlacement placement = PlanQuilt(sample, {90, 70, tileable, 3}, SmallBlocks());
    const SourceMap map = placement.RenderSourceMap();
    ASSERT_TRUE(map.Complete());
    const Image out = map.Apply(sample);
    ASSERT_EQ(out.width(), 90);
    ASSERT_EQ(out.height(), 70);
    for (int y = 0; y < out.height(); ++y) {
      for (int x = 0; x < out.width(); ++x) {
        const auto p = out.pixel(x, y);
        const auto found = pixels.find({p.begin(), p.end()});
        ASSERT_NE(found, pixels.end()) << "output pixel " << x << "," << y << " is no sample pixel";
        EXPECT_EQ(found->second, map.at(x, y));  // and all n maps came from the same pixel
      }
    }
  }
}

struct EqualityCase {
  ErrorMetric metric;
  bool tileable;
  bool coherence;
  int stride;
  const char* name;  // test name suffix (see overlap_search_test.cc)
};

void PrintTo(const EqualityCase& test, std::ostream* out) { *out << test.name; }

class QuiltSearchTest : public ::testing::TestWithParam<EqualityCase> {};

TEST_P(QuiltSearchTest, FastSearchChoosesTheBruteForceBlocks) {
  const EqualityCase& test = GetParam();
  const Image sample = MaterialMaps(SurfacePattern::kBumps, 40);
  QuiltOptions options = SmallBlocks();
  options.matching.metric = test.metric;
  options.coherence = test.coherence;
  options.candidate_stride = test.stride;
  options.search = SearchMode::kBruteForce;
  const BlockPlacement brute = PlanQuilt(sample, {80, 64, test.tileable, 5}, options);
  options.search = SearchMode::kFast;
  const BlockPlacement fast = PlanQuilt(sample, {80, 64, test.tileable, 5}, options);
  int searched = 0;
  for (const PlacedBlock& block : brute.blocks)
    searched += block.choice == PlacedBlock::Choice::kSearch;
  EXPECT_GT(searched, 10);
  ASSERT_EQ(fast.blocks.size(), brute.blocks.size());
  for (std::size_t i = 0; i < fast.blocks.size(); ++i) {
    EXPECT_EQ(fast.blocks[i].source, brute.blocks[i].source) << "block " << i;
  }
  EXPECT_EQ(fast, brute);  // cuts included
}

INSTANTIATE_TEST_SUITE_P(
    Modes, QuiltSearchTest,
    ::testing::Values(EqualityCase{ErrorMetric::kSsd, false, true, 1, "SsdCoherence"},
                      EqualityCase{ErrorMetric::kSsd, true, false, 1, "SsdTileable"},
                      EqualityCase{ErrorMetric::kSad, false, false, 1, "Sad"},
                      EqualityCase{ErrorMetric::kSad, true, true, 2, "SadTileableStride2"}),
    [](const ::testing::TestParamInfo<EqualityCase>& case_info) {
      return std::string(case_info.param.name);
    });

TEST(ImageQuiltingTest, SameSeedSameOutputOnAnyNumberOfThreads) {
  const Image sample = MaterialMaps(SurfacePattern::kBricks, 48);
  const SynthesisTarget target{100, 90, false, 42};
  const BlockPlacement reference = PlanQuilt(sample, target, {});
  EXPECT_EQ(PlanQuilt(sample, target, {}), reference);
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    EXPECT_EQ(PlanQuilt(sample, target, {}), reference);
  }
  SynthesisTarget other = target;
  other.seed = 43;
  EXPECT_NE(PlanQuilt(sample, other, {}).RenderSourceMap(), reference.RenderSourceMap());
}

// The output and its source map shifted circularly by half their size: the wrap moves inside.
std::pair<Image, SourceMap> Rolled(const Image& image, const SourceMap& map) {
  const int w = image.width(), h = image.height();
  Image out(w, h, image.channels());
  SourceMap rolled(w, h, map.sample_width(), map.sample_height());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int from_x = (x + w / 2) % w, from_y = (y + h / 2) % h;
      rolled.Set(x, y, map.at(from_x, from_y));
      for (int c = 0; c < image.channels(); ++c) out.at(x, y, c) = image.at(from_x, from_y, c);
    }
  }
  return {out, rolled};
}

// "Tileable output has no seam across the wrap": rolling the output by half its size moves the
// wrap inside; its seam score must not change, and neighbours across the wrap must differ as
// much as inside. A plain output shows the wrap as a seam.
TEST(ImageQuiltingTest, TileableOutputHasNoSeamAcrossTheWrap) {
  const Image sample = MaterialMaps(SurfacePattern::kBumps, 64);
  const ChannelTransform scale = ChannelTransform::Fit(sample, {});
  for (std::uint64_t seed : {1, 2, 3}) {
    for (bool tileable : {true, false}) {
      const SourceMap map = PlanQuilt(sample, {192, 160, tileable, seed}, {}).RenderSourceMap();
      const Image out = map.Apply(sample);
      const PairContrast wrap = WrapScore(out, scale);
      const PairContrast seams = SeamScore(out, map, scale);
      const auto [rolled, rolled_map] = Rolled(out, map);
      const double rolled_ratio = SeamScore(rolled, rolled_map, scale).ratio / seams.ratio;
      if (tileable) {
        EXPECT_NEAR(rolled_ratio, 1.0, 0.05) << "seed " << seed;
        EXPECT_GT(wrap.ratio, 0.33) << "seed " << seed;
        EXPECT_LT(wrap.ratio, 1.5) << "seed " << seed;
      } else {
        EXPECT_GT(rolled_ratio, 1.2) << "seed " << seed;
        EXPECT_GT(wrap.ratio, 4.0) << "seed " << seed;
      }
    }
  }
}

TEST(ImageQuiltingTest, TileableBlocksWrapOntoTheFirstRowAndColumn) {
  const Image sample = MaterialMaps(SurfacePattern::kBumps, 48);
  const BlockPlacement placement = PlanQuilt(sample, {100, 90, true, 7}, SmallBlocks());
  const int columns = static_cast<int>(placement.column_positions.size());
  const int rows = static_cast<int>(placement.row_positions.size());
  for (const PlacedBlock& block : placement.blocks) {
    EXPECT_EQ(block.overlap.right > 0, block.column == columns - 1);
    EXPECT_EQ(block.overlap.bottom > 0, block.row == rows - 1);
    EXPECT_EQ(block.cuts.right.empty(), block.overlap.right == 0);
    if (block.overlap.right > 0 || block.overlap.bottom > 0) {
      EXPECT_EQ(block.choice, PlacedBlock::Choice::kSearch) << "wrapping blocks are searched";
    }
  }
}

TEST(ImageQuiltingTest, MatchingMakesSeamsFainterThanRandomBlocks) {
  const Image sample = MaterialMaps(SurfacePattern::kGrooves, 64);
  const ChannelTransform scale = ChannelTransform::Fit(sample, {});
  QuiltOptions matched;
  matched.coherence = false;
  QuiltOptions random_blocks = matched;
  random_blocks.tolerance = 1e12;  // every candidate qualifies: blocks at random, still cut
  const SynthesisTarget target{128, 128, false, 9};
  const SourceMap good = PlanQuilt(sample, target, matched).RenderSourceMap();
  const SourceMap bad = PlanQuilt(sample, target, random_blocks).RenderSourceMap();
  const PairContrast good_seams = SeamScore(good.Apply(sample), good, scale);
  const PairContrast bad_seams = SeamScore(bad.Apply(sample), bad, scale);
  EXPECT_LT(good_seams.ratio, 0.5 * bad_seams.ratio);
  EXPECT_LT(good_seams.ratio, 3.0);
}

TEST(ImageQuiltingTest, CoherenceContinuesTheSampleUnlessSearchIsForced) {
  const Image sample = MaterialMaps(SurfacePattern::kBumps, 64);
  QuiltOptions options = SmallBlocks();
  options.forced_search_rate = 0.0;
  const BlockPlacement continued = PlanQuilt(sample, {120, 40, false, 2}, options);
  int coherent = 0;
  for (const PlacedBlock& block : continued.blocks) {
    if (block.choice != PlacedBlock::Choice::kCoherence) continue;
    ++coherent;
    const PlacedBlock& left = continued.blocks[&block - continued.blocks.data() - 1];
    if (block.row == left.row && block.column > 0 && block.overlap.top == 0) {
      EXPECT_EQ(block.source.x - left.source.x, block.x - left.x);
      EXPECT_EQ(block.source.y, left.source.y);
    }
  }
  EXPECT_GT(coherent, 3);
  options.forced_search_rate = 1.0;
  for (const PlacedBlock& block : PlanQuilt(sample, {120, 40, false, 2}, options).blocks) {
    EXPECT_NE(block.choice, PlacedBlock::Choice::kCoherence);
  }
}

TEST(ImageQuiltingTest, ZeroWeightChannelsDoNotGuide) {
  const Image guide = MaterialMaps(SurfacePattern::kBricks, 40);
  Image padded(40, 40, 8);
  const Image noise = RandomMaps(40, 40, 2, 3);
  for (std::size_t i = 0; i < padded.pixel_count(); ++i) {
    for (int c = 0; c < 6; ++c) padded.pixel(i)[c] = guide.pixel(i)[c];
    padded.pixel(i)[6] = noise.pixel(i)[0];
    padded.pixel(i)[7] = noise.pixel(i)[1];
  }
  QuiltOptions options = SmallBlocks();
  const BlockPlacement reference = PlanQuilt(guide, {70, 70, false, 4}, options);
  options.matching.weights = {1, 1, 1, 1, 1, 1, 0, 0};
  EXPECT_EQ(PlanQuilt(padded, {70, 70, false, 4}, options), reference);
  options.matching.weights = {1, 1, 1, 1, 1, 1, 1, 1};
  EXPECT_NE(PlanQuilt(padded, {70, 70, false, 4}, options), reference);
}

TEST(ImageQuiltingTest, DefaultsFollowTheThesis) {
  EXPECT_EQ(DefaultBlockSize(128, 128), 42);  // a third
  EXPECT_EQ(DefaultBlockSize(20, 40), 8);
  EXPECT_EQ(DefaultBlockSize(6, 40), 6);
  for (int block : {8, 12, 32, 48, 64}) {
    const int overlap = DefaultOverlap(block);
    EXPECT_GE(overlap, block / 6.0) << block;  // thesis: B/6 to B/3
    EXPECT_LE(overlap, block / 3.0) << block;
  }
  const BlockPlacement placement =
      PlanQuilt(MaterialMaps(SurfacePattern::kBumps, 64), {100, 100, false, 1}, {});
  EXPECT_EQ(placement.block_size, 21);
  EXPECT_EQ(placement.overlap, 5);
}

TEST(ImageQuiltingTest, DefaultsMakeCloserSeamsThanTheVarietyPreset) {
  EXPECT_EQ(VarietyQuiltOptions(150, 160).block_size, 37);
  EXPECT_EQ(VarietyQuiltOptions(12, 40).block_size, 8);
  EXPECT_EQ(VarietyQuiltOptions(300, 300).block_size, 64);
  for (SurfacePattern pattern : {SurfacePattern::kGrooves, SurfacePattern::kBumps}) {
    const Image sample = MaterialMaps(pattern, 72, 5);
    double default_distance = 0.0;
    double variety_distance = 0.0;
    for (std::uint64_t seed : {1, 2}) {
      const SynthesisTarget target{160, 160, false, seed};
      const SourceMap plain = PlanQuilt(sample, target, {}).RenderSourceMap();
      const SourceMap variety =
          PlanQuilt(sample, target, VarietyQuiltOptions(72, 72)).RenderSourceMap();
      default_distance += MeanNearestPatchDistance(sample, plain.Apply(sample));
      variety_distance += MeanNearestPatchDistance(sample, variety.Apply(sample));
    }
    EXPECT_LT(default_distance, variety_distance)
        << static_cast<int>(pattern) << ": " << default_distance << " vs " << variety_distance;
  }
}

TEST(ImageQuiltingTest, RejectsParametersOutOfRange) {
  const Image sample = MaterialMaps(SurfacePattern::kBumps, 32);
  const SynthesisTarget target{64, 64, false, 1};
  auto plan = [&](auto change, SynthesisTarget t) {
    QuiltOptions options = SmallBlocks();
    change(options);
    return PlanQuilt(sample, t, options);
  };
  EXPECT_THROW(plan([](QuiltOptions& o) { o.block_size = 33; }, target), Error);
  EXPECT_THROW(plan([](QuiltOptions& o) { o.overlap = 7; }, target), Error);
  EXPECT_THROW(plan([](QuiltOptions& o) { o.tolerance = -0.1; }, target), Error);
  EXPECT_THROW(plan([](QuiltOptions& o) { o.forced_search_rate = 1.5; }, target), Error);
  EXPECT_THROW(plan([](QuiltOptions& o) { o.candidate_stride = 0; }, target), Error);
  EXPECT_THROW(plan([](QuiltOptions&) {}, SynthesisTarget{0, 64, false, 1}), Error);
  EXPECT_THROW(plan([](QuiltOptions&) {}, SynthesisTarget{10, 64, true, 1}), Error);
  EXPECT_NO_THROW(plan([](QuiltOptions&) {}, SynthesisTarget{5, 7, false, 1}));  // crop of a block
}

}  // namespace
}  // namespace photomat

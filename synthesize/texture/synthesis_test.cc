#include "synthesize/texture/synthesis.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
#include "synthesize/texture/synthesis_quality.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

SynthesisOptions Grow(int width, int height, std::uint64_t seed = 3) {
  SynthesisOptions options;
  options.target = {width, height, false, seed};
  options.quilt.block_size = 12;
  options.quilt.overlap = 3;
  return options;
}

bool SameValues(const Image& a, const Image& b) {
  return a.SameShape(b) && std::equal(a.values().begin(), a.values().end(), b.values().begin());
}

// "A stack can be re-applied to other maps, like a coordinate transform": whichever
// representation is grown with the same guide, its pixels come from the same sample pixels, and
// relighting the grown stack equals growing the relit sample.
TEST(SynthesisTest, OneGuideGrowsEveryRepresentationAlike) {
  const testing::SyntheticSet synthetic = testing::LambertianSet(SurfacePattern::kBumps, 40);
  const Representation gradient = Fit(synthetic.set, Method::Parse("gradient"));
  const Image& guide = gradient.maps();
  const SynthesisOptions options = Grow(72, 64);
  const SynthesisPlan plan = PlanSynthesis(guide, options);
  const LightDirection light = LightDirection::FromSlantTilt(50.0, 120.0);
  for (const char* name : {"3i", "gradient", "ptm", "ptm-lrgb", "eigen3", "eigen6"}) {
    const Representation sample = Fit(synthetic.set, Method::Parse(name));
    const Representation grown = Synthesize(sample, options, nullptr, &guide);
    EXPECT_EQ(grown.method(), sample.method());
    EXPECT_EQ(grown.width(), 72);
    EXPECT_EQ(grown.maps().channel_names(), sample.maps().channel_names());
    EXPECT_TRUE(SameValues(grown.maps(), plan.source_map.Apply(sample.maps()))) << name;
    EXPECT_TRUE(SameValues(grown.Relight(light), plan.source_map.Apply(sample.Relight(light))))
        << name;
    EXPECT_EQ(grown.details()["synthesis"]["method"], "quilt");
    EXPECT_EQ(grown.details()["synthesis"]["quilt"]["block"], 12);
  }
}

TEST(SynthesisTest, PlainImagesAndThePixelMethodGrowToo) {
  const testing::SyntheticSet synthetic = testing::LambertianSet(SurfacePattern::kGrooves, 32);
  const Image& albedo = synthetic.material.albedo;
  SynthesisOptions options = Grow(50, 40);
  const SynthesisPlan quilt = PlanSynthesis(albedo, options);
  ASSERT_TRUE(quilt.placement.has_value());
  EXPECT_EQ(quilt.source_map.Apply(albedo).width(), 50);
  options.method = SynthesisMethod::kPixel;
  options.pixel.levels = 1;
  const SynthesisPlan pixel = PlanSynthesis(albedo, options);
  EXPECT_FALSE(pixel.placement.has_value());
  EXPECT_TRUE(pixel.source_map.Complete());
  EXPECT_EQ(pixel.description["method"], "pixel");
  EXPECT_EQ(ParseSynthesisMethod("pixel"), SynthesisMethod::kPixel);
  EXPECT_THROW(ParseSynthesisMethod("graphcut"), Error);
}

TEST(SynthesisTest, GrownStacksSaveAndRelightLikeTheSample) {
  const testing::SyntheticSet synthetic = testing::LambertianSet(SurfacePattern::kBricks, 32);
  const Representation ptm = Fit(synthetic.set, Method::Parse("ptm"));
  const Representation grown = Synthesize(ptm, Grow(48, 48));
  testing::TempDir dir;
  SaveRepresentation(dir / "grown.exr", grown);
  const LoadedStack loaded = LoadRepresentation(dir / "grown.exr");
  EXPECT_EQ(loaded.representation.details()["synthesis"]["width"], 48);
  const LightDirection light = LightDirection::FromSlantTilt(60.0, 60.0);
  EXPECT_TRUE(SameValues(loaded.representation.Relight(light), grown.Relight(light)));
}

TEST(SynthesisTest, RejectsAGuideOfAnotherSize) {
  const testing::SyntheticSet synthetic = testing::LambertianSet(SurfacePattern::kBumps, 32);
  const Representation gradient = Fit(synthetic.set, Method::Parse("gradient"));
  const Image other(30, 32, 3);
  EXPECT_THROW(Synthesize(gradient, Grow(40, 40), nullptr, &other), Error);
  SourceMap map(10, 10, 30, 32);
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 10; ++x) map.Set(x, y, {x, y});
  }
  EXPECT_THROW(ApplySourceMap(gradient, map), Error);
}

// The defaults a user gets (`photomat synthesize` without options: quilting, fast search, the
// default block, tolerance and error floor) on a real exemplar, as the command plans it.
SynthesisPlan PlanWithDefaults(const Image& sample, int size, std::uint64_t seed) {
  SynthesisOptions options;
  options.target = {size, size, false, seed};
  return PlanSynthesis(sample, options);
}

// Issue 18: the default preset's output is a function of the seed alone, on 1 and on 2 threads
// (blocks placed in waves, each from its own random stream), and the seed matters.
TEST(SynthesisTest, DefaultQuiltingOfARealExemplarIsTheSameOnOneAndTwoThreads) {
  PHOTOMAT_TEST_DATA_OR_SKIP(file, "textures/quilting/input3.png");
  const Image sample = ReadImage(file).image;
  auto plan_on = [&](int threads, std::uint64_t seed) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    return PlanWithDefaults(sample, 512, seed);
  };
  const SynthesisPlan one = plan_on(1, 11);
  const SynthesisPlan two = plan_on(2, 11);
  ASSERT_TRUE(one.placement && two.placement);
  EXPECT_EQ(*two.placement, *one.placement);
  EXPECT_EQ(two.source_map, one.source_map);
  EXPECT_TRUE(testing::SameBits(two.source_map.Apply(sample), one.source_map.Apply(sample)));
  EXPECT_EQ(plan_on(2, 11).source_map, one.source_map);  // and again
  EXPECT_NE(plan_on(2, 12).source_map, one.source_map);
}

// Issue 18: the defaults' nearest-patch distance at G'MIC's or below (target: at most 1.05 x
// G'MIC's syntexturize_matchpatch) on input1, the shared/data exemplar where they come closest
// to G'MIC, grown to 512 x 512 as in bench/synthesis_table, with their variety (coverage) kept.
TEST(SynthesisTest, DefaultQuiltingOfARealExemplarIsAsCloseToTheSampleAsGmic) {
  PHOTOMAT_TEST_DATA_OR_SKIP(file, "textures/quilting/input1.png");
  const Image sample = ReadImage(file).image;
  const SynthesisPlan plan = PlanWithDefaults(sample, 512, 1);
  const SynthesisQuality quality =
      MeasureSynthesis(sample, plan.source_map.Apply(sample), &plan.source_map);
  // G'MIC 2.9.4 (Debian 12) on input1, means of its runs in bench/synthesis_table and
  // bench/peer_table: 0.00426 (2 runs), 0.0042 (6 runs); the target is 1.05 x 0.00426 = 0.00447.
  // Measured: 0.00388; bound 0.00427 = 0.00388 * 1.1 (the former defaults: 0.00458).
  EXPECT_LT(quality.nearest_patch_distance, 0.00427);
  // Not by copying a few large pieces: measured coverage 0.823; bound 0.741 = 0.823 * 0.9.
  EXPECT_GT(quality.sample_coverage.value(), 0.741);
}

}  // namespace
}  // namespace photomat

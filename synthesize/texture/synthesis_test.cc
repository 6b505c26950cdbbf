#include "synthesize/texture/synthesis.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
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

}  // namespace
}  // namespace photomat

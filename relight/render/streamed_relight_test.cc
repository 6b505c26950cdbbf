#include "relight/render/streamed_relight.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "capture/io/load_photometric_set.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// The streamed images equal the in-memory ones value for value: every relit pixel depends on its
// own maps only, and Relight sums them in the same order in a band as in the whole image.
TEST(StreamedRelightTest, StreamedImagesEqualTheInMemoryRelightingForEveryMethod) {
  testing::TempDir dir;
  const auto synthetic = testing::ShadowedSpecularSet(24);
  const LightDirection light = LightDirection::FromSlantTilt(55, 140);
  for (const char* name : {"gradient", "ptm", "ptm-lrgb", "eigen6", "hsh9", "rbf"}) {
    const Representation fitted = Fit(synthetic.set, Method::Parse(name));
    const auto stack_path = dir / (std::string(name) + ".exr");
    SaveRepresentation(stack_path, fitted, {synthetic.set.lights(), "linear", "synthetic"});
    for (const RelitFormat format : {RelitFormat::kExr, RelitFormat::kPng16, RelitFormat::kPng8}) {
      StreamedRelightOptions options;
      options.output.format = format;
      options.output.relight.clamp_negative = format == RelitFormat::kExr;
      options.band_rows = 5;  // 5, 5, 5, 5 and 4 rows
      const auto whole = dir / fmt::format("{}-whole{}", name, Extension(format));
      const auto streamed = dir / fmt::format("{}-streamed{}", name, Extension(format));
      WriteRelitImage(whole, fitted, light, options.output);
      StackBandReader stack(stack_path);
      const StreamedRelightReport report = WriteRelitImageStreamed(streamed, stack, light, options);
      EXPECT_EQ(report.band_rows, 5);
      EXPECT_TRUE(testing::SameBits(ReadImage(streamed).image, ReadImage(whole).image))
          << name << " " << ToString(format);
    }
  }
}

TEST(StreamedRelightTest, StreamedSetEqualsTheInMemorySetAndReloads) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 20);
  const Representation ptm = Fit(synthetic.set, Method::Parse("ptm"));
  SaveRepresentation(dir / "ptm.exr", ptm, {synthetic.set.lights(), "linear", "synthetic"});
  const auto lights = LightSweep(6, 45);
  StreamedRelightOptions options;
  options.output.format = RelitFormat::kPng16;
  options.band_rows = 3;
  WriteRelitSet(dir / "whole", ptm, lights, options.output);
  StackBandReader stack(dir / "ptm.exr");
  const StreamedRelightReport report =
      WriteRelitSetStreamed(dir / "streamed", stack, lights, options);
  EXPECT_EQ(report.passes, 1);
  const LoadedSet whole = LoadPhotometricSet(dir / "whole");
  const LoadedSet streamed = LoadPhotometricSet(dir / "streamed");
  ASSERT_EQ(streamed.set.size(), 6);
  for (int i = 0; i < 6; ++i) {
    EXPECT_LT(streamed.set.light(i).AngleToDegrees(lights[i]), 1e-9);
    EXPECT_TRUE(testing::SameBits(streamed.set.image(i), whole.set.image(i))) << i;
  }
}

TEST(StreamedRelightTest, ManyLightsTakeSeveralPassesOverTheStack) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 8);
  const Representation gradient = Fit(synthetic.set, Method::Parse("gradient"));
  SaveRepresentation(dir / "g.exr", gradient);
  const auto lights = LightSweep(kRelitImagesPerPass + 6, 30);
  StreamedRelightOptions options;
  options.output.format = RelitFormat::kExr;
  StackBandReader stack(dir / "g.exr");
  const StreamedRelightReport report = WriteRelitSetStreamed(dir / "out", stack, lights, options);
  EXPECT_EQ(report.passes, 2);
  EXPECT_EQ(report.band_rows, 8);  // the default budget holds the whole small stack
  const Image last = ReadImage(dir / fmt::format("out/relit_{:03}.exr", lights.size() - 1)).image;
  EXPECT_TRUE(testing::SameBits(last, gradient.Relight(lights.back())));
}

TEST(StreamedRelightTest, BandHeightFollowsTheBudget) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  SaveRepresentation(dir / "ptm.exr", Fit(synthetic.set, Method::Parse("ptm")));
  StackBandReader stack(dir / "ptm.exr");
  // PTM: 18 maps stored and gathered (144 bytes per pixel), 3 relit channels per light (24).
  const std::size_t row = 16 * (144 + 24 * 2);
  EXPECT_EQ(RelightBandRows(5 * row, stack, 2), 5);
  EXPECT_EQ(RelightBandRows(5 * row - 1, stack, 2), 4);
  EXPECT_EQ(RelightBandRows(1, stack, 2), 1);
  EXPECT_EQ(RelightBandRows(std::size_t{1} << 30, stack, 2), 16);
}

TEST(StreamedRelightTest, AStackTruncatedMidWayLeavesNoImage) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 64);
  SaveRepresentation(dir / "g.exr", Fit(synthetic.set, Method::Parse("gradient")), {},
                     ExrCompression::kNone);
  std::filesystem::resize_file(dir / "g.exr", std::filesystem::file_size(dir / "g.exr") / 2);
  StackBandReader stack(dir / "g.exr");
  StreamedRelightOptions options;
  options.band_rows = 4;
  EXPECT_THAT(
      [&] {
        WriteRelitImageStreamed(dir / "x.png", stack, LightDirection::FromSlantTilt(30, 0),
                                options);
      },
      ThrowsMessage<Error>(HasSubstr("g.exr")));
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
  // Only the stack is left: no temporary file either.
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path()))
    ++files;
  EXPECT_EQ(files, 1);
}

}  // namespace
}  // namespace photomat

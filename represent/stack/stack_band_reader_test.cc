#include "represent/stack/stack_band_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/fit.h"
#include "represent/model/shading.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// Rows [first, first + count) of `image` as an image of their own.
Image RowsOf(const Image& image, int first, int count) {
  Image rows(image.Rows(first, count));
  rows.set_channel_names(image.channel_names());
  return rows;
}

TEST(StackBandReaderTest, BandsEqualTheWholeStackForEveryMethod) {
  testing::TempDir dir;
  const auto synthetic = testing::ShadowedSpecularSet(24);
  const StackProvenance provenance{synthetic.set.lights(), "linear", "synthetic"};
  for (const char* name : {"gradient", "ptm", "eigen6", "hsh9", "rbf"}) {
    const Representation fitted = Fit(synthetic.set, Method::Parse(name));
    const auto path = dir / (std::string(name) + ".exr");
    SaveRepresentation(path, fitted, provenance);
    const LoadedStack whole = LoadRepresentation(path);
    StackBandReader reader(path);
    EXPECT_EQ(reader.header().representation.method(), name);
    EXPECT_EQ(reader.header().provenance.capture_lights.size(), 36u);
    // Bands of 7 rows: 7, 7, 7 and a last one of 3.
    for (int first = 0; first < 24; first += 7) {
      const LoadedStack band = reader.ReadNext(7);
      const int rows = std::min(7, 24 - first);
      ASSERT_EQ(band.representation.height(), rows);
      EXPECT_EQ(band.representation.maps().channel_names(), fitted.maps().channel_names());
      EXPECT_TRUE(testing::SameBits(band.representation.maps(),
                                    RowsOf(whole.representation.maps(), first, rows)))
          << name << " rows from " << first;
      // The band relights to the rows of the whole relit image.
      const LightDirection light = LightDirection::FromSlantTilt(50, 120);
      EXPECT_TRUE(testing::SameBits(band.representation.Relight(light),
                                    RowsOf(whole.representation.Relight(light), first, rows)))
          << name;
    }
    EXPECT_THAT([&] { reader.ReadNext(1); },
                ThrowsMessage<Error>(HasSubstr("read past the last row")));
    reader.Rewind();
    EXPECT_TRUE(
        testing::SameBits(reader.ReadNext(24).representation.maps(), whole.representation.maps()));
  }
}

TEST(StackBandReaderTest, ExtraLayersComeInBandsToo) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const Representation ptm = Fit(synthetic.set, Method::Parse("ptm"));
  Image extra(16, 16, std::vector<std::string>{"height"});
  for (std::size_t p = 0; p < extra.pixel_count(); ++p) extra.pixel(p)[0] = 0.25f * p;
  SaveRepresentation(dir / "s.exr", ptm, {}, extra);
  StackBandReader reader(dir / "s.exr");
  EXPECT_EQ(reader.stored_channels(), ptm.maps().channels() + 1);
  reader.ReadNext(5);
  const LoadedStack band = reader.ReadNext(5);
  EXPECT_TRUE(testing::SameBits(band.extra_layers, RowsOf(extra, 5, 5)));
}

TEST(StackBandReaderTest, PbrStackKeepsItsShading) {
  testing::TempDir dir;
  Image maps(3, 4, MicrofacetShading().MapNames());
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    const float values[] = {0.5f, 0.4f, 0.3f, 0.3f + 0.1f * p, 0.05f, 0.1f, 0.0f, 0.995f};
    for (int c = 0; c < 8; ++c) maps.pixel(p)[c] = values[c];
  }
  const Representation pbr("pbr", maps, std::make_shared<MicrofacetShading>());
  SaveRepresentation(dir / "pbr.exr", pbr);
  StackBandReader reader(dir / "pbr.exr");
  reader.ReadNext(2);
  const LoadedStack band = reader.ReadNext(2);
  ASSERT_NE(band.representation.shading(), nullptr);
  const LightDirection light = LightDirection::FromSlantTilt(20, 10);
  EXPECT_TRUE(
      testing::SameBits(band.representation.Relight(light), RowsOf(pbr.Relight(light), 2, 2)));
}

TEST(StackBandReaderTest, PlainExrIsNotAStack) {
  testing::TempDir dir;
  WriteImage(dir / "plain.exr", Image(2, 2, 3));
  EXPECT_THAT([&] { StackBandReader reader(dir / "plain.exr"); },
              ThrowsMessage<Error>(HasSubstr("plain.exr: not a photomat map stack")));
  EXPECT_TRUE(IsStreamableStack("a/b.EXR"));
  EXPECT_FALSE(IsStreamableStack("a/b.ptm"));
}

}  // namespace
}  // namespace photomat

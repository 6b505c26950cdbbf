#include "represent/stack/map_stack.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/image_io.h"
#include "core/random.h"
#include "represent/fitting/fit.h"
#include "represent/model/neural_decoder.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(MapStackTest, EveryMethodRoundTripsExactly) {
  testing::TempDir dir;
  const auto synthetic = testing::ShadowedSpecularSet(24);
  std::vector<Method> methods = AllMethods();
  for (const char* name : {"hsh9", "rbf", "bilinear"}) methods.push_back(Method::Parse(name));
  for (const Method& method : methods) {
    const Representation fitted = Fit(synthetic.set, method);
    const auto path = dir / (method.Name() + ".exr");
    SaveRepresentation(path, fitted, {synthetic.set.lights(), "linear", "synthetic"});
    const LoadedStack loaded = LoadRepresentation(path);
    const Representation& r = loaded.representation;
    EXPECT_EQ(r.method(), method.Name());
    EXPECT_EQ(r.maps().channel_names(), fitted.maps().channel_names());
    EXPECT_EQ(loaded.provenance.capture_lights.size(), 36u);
    for (const auto& light :
         {LightDirection::FromSlantTilt(60, 60), LightDirection::FromSlantTilt(38, 200)}) {
      const Image a = fitted.Relight(light), b = r.Relight(light);
      for (std::size_t v = 0; v < a.values().size(); ++v) {
        ASSERT_EQ(a.values()[v], b.values()[v]) << method.Name();
      }
    }
  }
}

TEST(MapStackTest, ProvenanceKeepsHowEachImageWasDecoded) {
  testing::TempDir dir;
  const auto synthetic = testing::ShadowedSpecularSet(24);
  StackProvenance provenance{synthetic.set.lights(), "linear", "synthetic"};
  provenance.images = {{"img_000.png", "srgb", "png-srgb", "PNG sRGB chunk"},
                       {"img_001.png", "gamma 2.2", "png-gama", "PNG gAMA 0.45455"}};
  SaveRepresentation(dir / "s.exr", Fit(synthetic.set, Method::Parse("gradient")), provenance);
  const StackProvenance loaded = LoadRepresentation(dir / "s.exr").provenance;
  ASSERT_EQ(loaded.images.size(), 2u);
  EXPECT_EQ(loaded.images[1].file, "img_001.png");
  EXPECT_EQ(loaded.images[1].encoding, "gamma 2.2");
  EXPECT_EQ(loaded.images[1].decided_by, "png-gama");
  EXPECT_EQ(loaded.images[1].evidence, "PNG gAMA 0.45455");
}

TEST(MapStackTest, PbrStackRoundTripsWithItsShading) {
  testing::TempDir dir;
  Image maps(3, 2, MicrofacetShading().MapNames());
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    const float values[] = {0.5f, 0.4f, 0.3f, 0.3f + 0.1f * p, 0.05f, 0.1f, 0.0f, 0.995f};
    for (int c = 0; c < 8; ++c) maps.pixel(p)[c] = values[c];
  }
  const Representation pbr("pbr", maps, std::make_shared<MicrofacetShading>(), {{"x", 1}});
  const auto path = dir / "pbr.exr";
  SaveRepresentation(path, pbr);
  const LoadedStack loaded = LoadRepresentation(path);
  ASSERT_NE(loaded.representation.shading(), nullptr);
  EXPECT_EQ(loaded.representation.shading()->kind(), "microfacet");
  const LightDirection light = LightDirection::FromSlantTilt(20, 10);
  const Image a = pbr.Relight(light), b = loaded.representation.Relight(light);
  for (std::size_t v = 0; v < a.values().size(); ++v) ASSERT_EQ(a.values()[v], b.values()[v]);
  EXPECT_GT(a.at(0, 0, 0), 0.0f);
}

// The neural basis's decoder travels in the description: reloaded, it relights bit for bit.
TEST(MapStackTest, NeuralStackRoundTripsWithItsDecoder) {
  testing::TempDir dir;
  Random random(9);
  auto weights = [&](int rows, int cols) {
    Eigen::MatrixXf m(rows, cols);
    for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = static_cast<float>(random.Normal());
    return m;
  };
  std::vector<DenseLayer> layers;
  layers.push_back({weights(5, 5), weights(5, 1).col(0)});
  layers.push_back({weights(3, 5), weights(3, 1).col(0)});
  auto shading = std::make_shared<NeuralShading>(NeuralDecoder(std::move(layers), 0.3f));
  Image maps(4, 3, shading->MapNames());
  for (float& v : maps.values()) v = static_cast<float>(random.Normal());
  const Representation neural("neural", maps, shading);
  const auto path = dir / "neural.exr";
  SaveRepresentation(path, neural);
  const LoadedStack loaded = LoadRepresentation(path);
  ASSERT_NE(loaded.representation.shading(), nullptr);
  EXPECT_EQ(loaded.representation.shading()->kind(), "neural");
  EXPECT_EQ(loaded.representation.maps().channel_names(),
            (std::vector<std::string>{"neural.0", "neural.1", "neural.2"}));
  for (const auto& light :
       {LightDirection::FromSlantTilt(20, 10), LightDirection::FromSlantTilt(65, 250)}) {
    const Image a = neural.Relight(light), b = loaded.representation.Relight(light);
    for (std::size_t v = 0; v < a.values().size(); ++v) ASSERT_EQ(a.values()[v], b.values()[v]);
  }
}

TEST(MapStackTest, ExtraLayersTravelBesideTheMaps) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const Representation ptm = Fit(synthetic.set, Method::Parse("ptm"));
  Image extra(16, 16, std::vector<std::string>{"height"});
  for (std::size_t p = 0; p < extra.pixel_count(); ++p) extra.pixel(p)[0] = 0.25f * p;
  SaveRepresentation(dir / "s.exr", ptm, {}, extra);
  const LoadedStack loaded = LoadRepresentation(dir / "s.exr");
  EXPECT_EQ(loaded.extra_layers.channel_names(), std::vector<std::string>{"height"});
  EXPECT_EQ(loaded.extra_layers.values()[37], 0.25f * 37);
  EXPECT_EQ(loaded.representation.maps().channel_names(), ptm.maps().channel_names());
  EXPECT_TRUE(LoadRepresentation([&] {
                SaveRepresentation(dir / "plain.exr", ptm);
                return dir / "plain.exr";
              }())
                  .extra_layers.empty());
  Image clash(16, 16, std::vector<std::string>{"ptm.a0.R"});
  EXPECT_THAT([&] { SaveRepresentation(dir / "bad.exr", ptm, {}, clash); },
              ThrowsMessage<Error>(HasSubstr("extra layer \"ptm.a0.R\" repeats a map")));
}

TEST(MapStackTest, PlainExrIsNotAStack) {
  testing::TempDir dir;
  WriteImage(dir / "plain.exr", Image(2, 2, 3));
  EXPECT_THAT([&] { LoadRepresentation(dir / "plain.exr"); },
              ThrowsMessage<Error>(HasSubstr("plain.exr: not a photomat map stack")));
}

TEST(MapStackTest, DamagedDescriptionIsNamed) {
  testing::TempDir dir;
  ImageWriteOptions options;
  options.attributes[kStackAttribute] = R"({"format": "photomat-map-stack", "version": 1,
      "method": "ptm", "layout": {"basis_size": 6, "basis_per_channel": true, "has_gain": false,
      "output_channels": 1}, "channels": ["a"], "basis": {"kind": "ptm"}})";
  WriteImage(dir / "bad.exr", Image(2, 2, 1), options);
  EXPECT_THAT([&] { LoadRepresentation(dir / "bad.exr"); },
              ThrowsMessage<Error>(HasSubstr("bad.exr: photomat:stack.channels: 1 names for a "
                                             "layout of 6 maps")));
}

TEST(MapStackTest, FitFolderResolvesByMethod) {
  testing::TempDir dir;
  testing::WriteFile(dir / "gradient.exr", "x");
  testing::WriteFile(dir / "ptm.exr", "x");
  WriteFitManifest(dir.path(), "in", {{"gradient", "gradient.exr"}, {"ptm", "ptm.exr"}});
  EXPECT_EQ(ResolveStack(dir.path(), "ptm"), dir / "ptm.exr");
  EXPECT_THAT([&] { ResolveStack(dir.path(), std::nullopt); },
              ThrowsMessage<Error>(HasSubstr("several stacks (gradient, ptm)")));
  EXPECT_THAT(
      [&] { ResolveStack(dir.path(), "eigen3"); },
      ThrowsMessage<Error>(HasSubstr("no \"eigen3\" stack here; available: gradient, ptm")));
}

}  // namespace
}  // namespace photomat

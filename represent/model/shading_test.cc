#include "represent/model/shading.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "core/microfacet_brdf.h"
#include "represent/model/representation.h"

namespace photomat {
namespace {

// Two pixels of pbr maps: a tilted glossy one and a flat matte one.
Image PbrMaps() {
  Image maps(2, 1, MicrofacetShading().MapNames());
  const Eigen::Vector3d tilted = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const float glossy[] = {0.6f,
                          0.3f,
                          0.2f,
                          0.4f,
                          0.08f,
                          static_cast<float>(tilted.x()),
                          static_cast<float>(tilted.y()),
                          static_cast<float>(tilted.z())};
  const float matte[] = {0.5f, 0.5f, 0.5f, 0.7f, 0.0f, 0.0f, 0.0f, 1.0f};
  for (int c = 0; c < 8; ++c) {
    maps.pixel(0, 0)[c] = glossy[c];
    maps.pixel(1, 0)[c] = matte[c];
  }
  return maps;
}

TEST(ShadingTest, PbrRelightsThroughTheMicrofacetBrdf) {
  const Representation r("pbr", PbrMaps(), std::make_shared<MicrofacetShading>());
  EXPECT_EQ(r.basis().kind(), "direction");
  EXPECT_FALSE(r.basis().LinearInLight());
  EXPECT_EQ(r.layout().MapCount(), 8);
  const LightDirection light = LightDirection::FromSlantTilt(35, 300);
  const Image relit = r.Relight(light);
  ASSERT_EQ(relit.channels(), 3);
  const Eigen::Vector3d l = light.vector();
  const float lf[3] = {static_cast<float>(l.x()), static_cast<float>(l.y()),
                       static_cast<float>(l.z())};
  for (int x = 0; x < 2; ++x) {
    const auto m = r.maps().pixel(x, 0);
    const float normal[3] = {m[5], m[6], m[7]};
    const MicrofacetResponse<float> expected = MicrofacetRadiance(normal, lf, m[3], m[4]);
    std::vector<float> one(3);
    r.RelightPixel(m, r.basis().Coefficients(light).cast<float>(), one);
    for (int c = 0; c < 3; ++c) {
      EXPECT_FLOAT_EQ(relit.at(x, 0, c), expected.diffuse * m[c] + expected.specular);
      EXPECT_FLOAT_EQ(one[c], relit.at(x, 0, c));
    }
  }
  const std::optional<Image> normals = EstimateNormals(r);
  ASSERT_TRUE(normals);
  EXPECT_FLOAT_EQ(normals->at(0, 0, 0), r.maps().at(0, 0, 5));
  EXPECT_FLOAT_EQ(normals->at(1, 0, 2), 1.0f);
}

TEST(ShadingTest, NewMapsKeepTheShading) {
  const Representation r("pbr", PbrMaps(), std::make_shared<MicrofacetShading>(), {{"a", 1}});
  const Representation copy = r.WithMapsAndDetails(PbrMaps(), {{"b", 2}});
  ASSERT_NE(copy.shading(), nullptr);
  EXPECT_EQ(copy.shading()->kind(), "microfacet");
  EXPECT_EQ(copy.details()["b"], 2);
  EXPECT_NE(r.WithMaps(PbrMaps()).shading(), nullptr);
  EXPECT_THROW(Representation("pbr", Image(2, 1, 6), std::make_shared<MicrofacetShading>()), Error);
}

TEST(ShadingTest, ShadingReadsBackFromItsJson) {
  const nlohmann::json json = MicrofacetShading().ToJson();
  EXPECT_EQ(PixelShadingFromJson(JsonReader(json, "x.exr"))->kind(), "microfacet");
  const nlohmann::json unknown = {{"kind", "phong"}};
  EXPECT_THROW(PixelShadingFromJson(JsonReader(unknown, "x.exr")), Error);
}

}  // namespace
}  // namespace photomat

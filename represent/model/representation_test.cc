#include "represent/model/representation.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace photomat {
namespace {

TEST(RepresentationTest, SharedBasisWithGainIsAlbedoTimesDot) {
  // Gradient layout: normal (shared) x albedo (gain).
  Image maps(1, 1,
             std::vector<std::string>{"normal.X", "normal.Y", "normal.Z", "albedo.R", "albedo.G",
                                      "albedo.B"});
  const float values[] = {0.0f, 0.6f, 0.8f, 0.5f, 0.25f, 1.0f};
  std::copy(std::begin(values), std::end(values), maps.values().begin());
  const Representation r("gradient", maps, {3, false, true, 3}, LinearLightBasis::Lambertian());
  const auto light = LightDirection::FromVector(0.0, 0.6, 0.8);  // n . l = 1
  const Image relit = r.Relight(light);
  EXPECT_FLOAT_EQ(relit.at(0, 0, 0), 0.5f);
  EXPECT_FLOAT_EQ(relit.at(0, 0, 1), 0.25f);
  EXPECT_FLOAT_EQ(relit.at(0, 0, 2), 1.0f);
  EXPECT_EQ(relit.channel_names(), (std::vector<std::string>{"R", "G", "B"}));
}

TEST(RepresentationTest, NegativeShadingClampsOnlyWhenAsked) {
  Image maps(1, 1, std::vector<std::string>{"normal.X", "normal.Y", "normal.Z", "albedo.Y"});
  const float values[] = {0.0f, 0.0f, 1.0f, 1.0f};
  std::copy(std::begin(values), std::end(values), maps.values().begin());
  const Representation r("gradient", maps, {3, false, true, 1}, LinearLightBasis::Lambertian());
  const auto below = LightDirection::FromVector(1.0, 0.0, 0.0);
  EXPECT_FLOAT_EQ(r.Relight(below).at(0, 0, 0), 0.0f);
  const auto tilted = LightDirection::FromVector(0.0, 0.0, 1.0);
  EXPECT_FLOAT_EQ(r.Relight(tilted, {.clamp_negative = true}).at(0, 0, 0), 1.0f);
}

TEST(RepresentationTest, LayoutMismatchIsAnError) {
  EXPECT_THROW(
      Representation("ptm", Image(2, 2, 5), {6, true, false, 1}, std::make_shared<PtmLightBasis>()),
      Error);
  EXPECT_THROW(
      Representation("ptm", Image(2, 2, 6), {6, true, false, 1}, LinearLightBasis::Lambertian()),
      Error);
}

}  // namespace
}  // namespace photomat

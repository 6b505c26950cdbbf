#include "core/photometric_set.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;

Image Filled(int w, int h, int c, float value) {
  Image image(w, h, c);
  for (float& v : image.values()) v = value;
  return image;
}

std::string MessageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(PhotometricSetTest, RejectsMixedSizesNamingBothImages) {
  const std::string message = MessageOf([] {
    PhotometricSet({Filled(4, 3, 1, 0), Filled(5, 3, 1, 0)},
                   {LightDirection::FromSlantTilt(0, 0), LightDirection::FromSlantTilt(30, 0)},
                   {"a.png", "b.png"}, "set.lp");
  });
  EXPECT_THAT(message, HasSubstr("set.lp"));
  EXPECT_THAT(message, HasSubstr("b.png is 5x3 but a.png is 4x3"));
}

TEST(PhotometricSetTest, RejectsMixedChannelCounts) {
  EXPECT_THAT(MessageOf([] {
                PhotometricSet(
                    {Filled(4, 3, 1, 0), Filled(4, 3, 3, 0)},
                    {LightDirection::FromSlantTilt(0, 0), LightDirection::FromSlantTilt(30, 0)});
              }),
              HasSubstr("channels"));
}

TEST(PhotometricSetTest, RejectsLightCountMismatch) {
  EXPECT_THAT(MessageOf([] { PhotometricSet({Filled(4, 3, 1, 0)}, {}); }),
              HasSubstr("1 images but 0 light directions"));
}

TEST(PhotometricSetTest, ApplyIntensitiesDividesEachChannel) {
  PhotometricSet set({Filled(2, 2, 3, 1.0f)}, {LightDirection::FromSlantTilt(0, 0)});
  set.set_intensities({{2.0f, 4.0f, 0.5f}});
  set.ApplyIntensities();
  EXPECT_FLOAT_EQ(set.image(0).at(1, 1, 0), 0.5f);
  EXPECT_FLOAT_EQ(set.image(0).at(1, 1, 1), 0.25f);
  EXPECT_FLOAT_EQ(set.image(0).at(1, 1, 2), 2.0f);
  EXPECT_TRUE(set.intensities().empty());
}

TEST(PhotometricSetTest, RejectsNonPositiveIntensity) {
  PhotometricSet set({Filled(2, 2, 1, 1.0f)}, {LightDirection::FromSlantTilt(0, 0)});
  EXPECT_THROW(set.set_intensities({{0.0f}}), Error);
  EXPECT_THROW(set.set_intensities({{1.0f, 1.0f}}), Error);
}

TEST(PhotometricSetTest, MaskMustMatchAndSelectSomething) {
  PhotometricSet set({Filled(2, 2, 1, 1.0f)}, {LightDirection::FromSlantTilt(0, 0)});
  EXPECT_THROW(set.set_mask(Mask(3, 2, true)), Error);
  EXPECT_THROW(set.set_mask(Mask(2, 2, false)), Error);
  set.set_mask(Mask(2, 2, true));
  EXPECT_EQ(set.mask()->CountSet(), 4u);
}

TEST(PhotometricSetTest, SubsetKeepsLightsNamesAndMask) {
  PhotometricSet set({Filled(2, 2, 1, 1), Filled(2, 2, 1, 2), Filled(2, 2, 1, 3)},
                     {LightDirection::FromSlantTilt(10, 0), LightDirection::FromSlantTilt(20, 0),
                      LightDirection::FromSlantTilt(30, 0)},
                     {"a", "b", "c"});
  set.set_mask(Mask(2, 2, true));
  const std::vector<int> pick = {2, 0};
  const PhotometricSet subset = set.Subset(pick);
  ASSERT_EQ(subset.size(), 2);
  EXPECT_EQ(subset.image_name(0), "c");
  EXPECT_FLOAT_EQ(subset.image(1).at(0, 0, 0), 1.0f);
  EXPECT_NEAR(subset.light(0).SlantDegrees(), 30, 1e-9);
  EXPECT_TRUE(subset.mask().has_value());
}

TEST(PhotometricSetTest, NearLampsAreCheckedAndFollowSubsets) {
  PhotometricSet set({Filled(4, 2, 1, 1), Filled(4, 2, 1, 2)},
                     {LightDirection::FromSlantTilt(10, 0), LightDirection::FromSlantTilt(20, 0)});
  NearLighting lighting;
  lighting.lamps = {NearLight{{1, 2, 30}, 1.0}, NearLight{{3, 4, 40}, 1.0}};
  lighting.width = 4;
  lighting.height = 6;
  lighting.first_row = 4;  // rows 4-5 of a 4 x 6 capture
  NearLighting one_lamp = lighting;
  one_lamp.lamps.pop_back();
  EXPECT_THAT([&] { set.set_near_lighting(one_lamp); },
              ::testing::ThrowsMessage<Error>(HasSubstr("1 near lamps for 2 images")));
  NearLighting past_the_end = lighting;
  past_the_end.first_row = 5;
  EXPECT_THAT([&] { set.set_near_lighting(past_the_end); },
              ::testing::ThrowsMessage<Error>(HasSubstr("frame is 4x6")));
  NearLighting below = lighting;
  below.lamps[1].position.z() = 0.0;
  EXPECT_THROW(set.set_near_lighting(below), Error);
  set.set_near_lighting(lighting);
  const std::vector<int> second = {1};
  const PhotometricSet subset = set.Subset(second);
  ASSERT_TRUE(subset.near_lighting());
  ASSERT_EQ(subset.near_lighting()->lamps.size(), 1u);
  EXPECT_EQ(subset.near_lighting()->lamps[0].position, Eigen::Vector3d(3, 4, 40));
  EXPECT_EQ(subset.near_lighting()->first_row, 4);
}

}  // namespace
}  // namespace photomat

#include "capture/io/capture_manifest.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "capture/io/load_photometric_set.h"
#include "capture/io/streamed_set.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

std::filesystem::path WriteManifest(const testing::TempDir& dir, const std::string& images,
                                    const std::string& extra = "") {
  const auto path = dir / "manifest.json";
  testing::WriteFile(path, "{\"format\": \"photomat-capture\", \"version\": 1" + extra +
                               ", \"images\": [" + images + "]}");
  return path;
}

TEST(CaptureManifestTest, LightsAsVectorsOrSlantTilt) {
  testing::TempDir dir;
  const auto path = WriteManifest(
      dir,
      R"({"file": "a.png", "light": [0, 0, 2]}, {"file": "b.png", "slant_deg": 45, "tilt_deg": 90,
          "intensity": [1, 2, 3]})",
      R"(, "colour_space": "sRGB", "mask": "m.png")");
  const CaptureManifest manifest = ReadCaptureManifest(path);
  ASSERT_EQ(manifest.images.size(), 2u);
  EXPECT_DOUBLE_EQ(manifest.images[0].light.z(), 1.0);
  EXPECT_NEAR(manifest.images[1].light.y(), std::sqrt(0.5), 1e-15);
  EXPECT_EQ(manifest.images[1].intensity, (std::vector<float>{1, 2, 3}));
  EXPECT_EQ(manifest.colour_space, ColourSpace::kSrgb);
  EXPECT_EQ(manifest.mask, "m.png");
}

TEST(CaptureManifestTest, DisagreeingVectorAndAnglesAreRejected) {
  testing::TempDir dir;
  const auto path = WriteManifest(
      dir, R"({"file": "a.png", "light": [0, 0, 1], "slant_deg": 10, "tilt_deg": 0})");
  EXPECT_THAT([&] { ReadCaptureManifest(path); },
              ThrowsMessage<Error>(HasSubstr("images[0]: \"light\" and \"slant_deg\"/\"tilt_deg\" "
                                             "disagree by 10.000 degrees")));
}

TEST(CaptureManifestTest, ImageWithoutLightIsRejected) {
  testing::TempDir dir;
  const auto path = WriteManifest(dir, R"({"file": "a.png", "slant": 10})");
  EXPECT_THAT([&] { ReadCaptureManifest(path); },
              ThrowsMessage<Error>(HasSubstr("images[0]: no light")));
}

TEST(CaptureManifestTest, WrongFormatIsRejected) {
  testing::TempDir dir;
  testing::WriteFile(dir / "m.json", R"({"images": []})");
  EXPECT_THAT([&] { ReadCaptureManifest(dir / "m.json"); },
              ThrowsMessage<Error>(HasSubstr("not a photomat capture manifest")));
}

TEST(CaptureManifestTest, UnknownColourSpaceIsRejected) {
  testing::TempDir dir;
  const auto path =
      WriteManifest(dir, R"({"file": "a.png", "light": [0, 0, 1]})", R"(, "colour_space": "P3")");
  EXPECT_THAT([&] { ReadCaptureManifest(path); },
              ThrowsMessage<Error>(HasSubstr("colour_space: expected \"linear\" or \"srgb\"")));
}

TEST(CaptureManifestTest, SaveThenLoadKeepsSixteenBitDataLightsAndMask) {
  testing::TempDir dir;
  std::vector<Image> images;
  for (int i = 0; i < 3; ++i) {
    Image image(5, 4, 3);
    for (std::size_t v = 0; v < image.values().size(); ++v) {
      image.values()[v] = static_cast<float>((v * 131 + i * 977) % 65536) / 65535.0f;
    }
    images.push_back(image);
  }
  PhotometricSet set(images,
                     {LightDirection::FromSlantTilt(30, 0), LightDirection::FromSlantTilt(30, 120),
                      LightDirection::FromSlantTilt(45, 240)});
  Mask mask(5, 4, true);
  mask.Set(0, 0, false);
  set.set_mask(mask);
  SavePhotometricSet(dir.path(), set);
  const LoadedSet loaded = LoadPhotometricSet(dir.path());
  ASSERT_EQ(loaded.set.size(), 3);
  EXPECT_EQ(loaded.set.mask()->CountSet(), 19u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(loaded.set.light(i).AngleToDegrees(set.light(i)), 1e-9);
    for (std::size_t v = 0; v < images[i].values().size(); ++v) {
      ASSERT_EQ(loaded.set.image(i).values()[v], images[i].values()[v]);
    }
  }
}

TEST(CaptureManifestTest, NearLampsTravelWithTheCaptureIntoEveryBand) {
  testing::TempDir dir;
  std::vector<Image> images(2, Image(6, 5, 3));
  PhotometricSet set(
      images, {LightDirection::FromSlantTilt(30, 0), LightDirection::FromSlantTilt(30, 180)});
  NearLighting lighting;
  lighting.lamps = {NearLight{{40, 0, 70}, 1.0}, NearLight{{-40, 0.5, 70.25}, 1.0}};
  lighting.width = 6;
  lighting.height = 5;
  set.set_near_lighting(lighting);
  SavePhotometricSet(dir.path(), set);
  const CaptureManifest manifest = ReadCaptureManifest(dir / "manifest.json");
  ASSERT_TRUE(manifest.images[1].lamp);
  EXPECT_EQ(*manifest.images[1].lamp, Eigen::Vector3d(-40, 0.5, 70.25));
  const LoadedSet loaded = LoadPhotometricSet(dir.path());
  ASSERT_TRUE(loaded.set.near_lighting());
  EXPECT_EQ(loaded.set.near_lighting()->lamps[0].position, Eigen::Vector3d(40, 0, 70));
  EXPECT_EQ(loaded.set.near_lighting()->height, 5);
  // A streamed band of rows 2-4 keeps the whole frame and knows where it starts.
  StreamedSet streamed = OpenStreamedSet(dir.path());
  streamed.ReadBand(2);
  const PhotometricSet band = streamed.ReadBand(3);
  ASSERT_TRUE(band.near_lighting());
  EXPECT_EQ(band.near_lighting()->first_row, 2);
  EXPECT_EQ(band.near_lighting()->height, 5);
  EXPECT_EQ(band.near_lighting()->lamps[1].position, Eigen::Vector3d(-40, 0.5, 70.25));
}

TEST(CaptureManifestTest, LampsForSomeImagesOnlyOrBelowThePlaneAreRejected) {
  testing::TempDir dir;
  EXPECT_THAT(
      [&] {
        ReadCaptureManifest(
            WriteManifest(dir, R"({"file": "a.png", "light": [0, 0, 1], "lamp": [0, 0, 90]},
                    {"file": "b.png", "light": [0, 1, 1]})"));
      },
      ThrowsMessage<Error>(HasSubstr("for all or none")));
  EXPECT_THAT(
      [&] {
        ReadCaptureManifest(
            WriteManifest(dir, R"({"file": "a.png", "light": [0, 0, 1], "lamp": [0, 0, -5]})"));
      },
      ThrowsMessage<Error>(HasSubstr("above the sample plane")));
}

}  // namespace
}  // namespace photomat

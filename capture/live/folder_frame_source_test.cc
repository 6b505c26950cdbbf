#include "capture/live/folder_frame_source.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;

TEST(FolderFrameSourceTest, ServesTheImageOfTheLightThatIsOn) {
  testing::TempDir dir;
  SyntheticMaterialOptions material_options;
  material_options.width = 16;
  material_options.height = 12;
  const SyntheticMaterial material = MakeSyntheticMaterial(material_options);
  const PhotometricSet set = RenderSyntheticCapture(material, ThesisLightGrid());
  SaveSetOptions save;
  save.sample_type = SampleType::kFloat;
  WriteSyntheticCapture(dir.path(), material, set, save);

  FolderFrameSource source(dir.path());
  EXPECT_EQ(source.DefaultFormat(), (FrameFormat{PixelFormat::kFloat, 16, 12}));
  EXPECT_EQ(source.SetFormat({PixelFormat::kFloat, 0, 0}), source.DefaultFormat());
  const auto grid = ThesisLightGrid();
  source.LightChanged({8, 36, grid[7]});
  Frame frame = source.Grab(std::chrono::milliseconds(10));
  ASSERT_TRUE(frame.image.SameShape(set.image(7)));
  for (std::size_t i = 0; i < frame.image.values().size(); ++i) {
    ASSERT_EQ(frame.image.values()[i], set.image(7).values()[i]);
  }
  source.LightChanged({0, 36, std::nullopt});
  frame = source.Grab(std::chrono::milliseconds(10));
  for (float v : frame.image.values()) ASSERT_EQ(v, 0.0f);

  try {
    source.LightChanged({1, 1, LightDirection::FromSlantTilt(10, 0)});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("no image for light 1 (slant 10.00, tilt 0.00): the nearest "
                                    "light of the set is 20.00 degrees away"));
  }
  EXPECT_THROW(source.SetFormat({PixelFormat::kYuyv, 16, 12}), Error);
  EXPECT_THROW(source.SetFormat({PixelFormat::kFloat, 32, 12}), Error);
}

}  // namespace
}  // namespace photomat

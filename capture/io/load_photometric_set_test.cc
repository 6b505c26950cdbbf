#include "capture/io/load_photometric_set.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "capture/io/capture_manifest.h"
#include "capture/io/streamed_set.h"
#include "core/error.h"
#include "core/image_io.h"
#include "tests/support/layouts.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using testing::Layouts;
using testing::LayoutWriter;
using testing::TempDir;
using testing::WriteImages;

class LoaderTest : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    layout_ = Layouts()[GetParam()];
    WriteImages(dir_.path(), names_);
  }
  void WriteLights(std::vector<std::string> lights, int count = -1) {
    layout_.write_lights(dir_.path(), names_, lights,
                         count < 0 ? static_cast<int>(lights.size()) : count);
  }
  void WriteGoodLights() { WriteLights(good_lights_); }
  std::string LoadError() {
    try {
      LoadPhotometricSet(dir_.path());
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  }

  TempDir dir_;
  LayoutWriter layout_;
  std::vector<std::string> names_ = {"a.png", "b.png", "c.png", "d.png"};
  std::vector<std::string> good_lights_ = {"0.5 0 0.866", "0 0.5 0.866", "-0.5 0 0.866",
                                           "0 -0.5 0.866"};
};

TEST_P(LoaderTest, LoadsAValidSet) {
  WriteGoodLights();
  const LoadedSet loaded = LoadPhotometricSet(dir_.path());
  EXPECT_EQ(loaded.kind, layout_.kind);
  EXPECT_EQ(loaded.set.size(), 4);
  EXPECT_EQ(loaded.set.width(), 6);
  EXPECT_EQ(loaded.set.channels(), 3);
  EXPECT_NEAR(loaded.set.light(1).y(), 0.5 / std::hypot(0.5, 0.866), 1e-12);
  // Each image keeps its file's channel names, as ReadImage gives them.
  for (int i = 0; i < loaded.set.size(); ++i) {
    EXPECT_EQ(loaded.set.image(i).channel_names(),
              ReadImage(dir_.path() / names_[i]).image.channel_names());
    EXPECT_EQ(loaded.set.image(i).channel_names().size(), 3u);
  }
}

TEST_P(LoaderTest, MissingImage) {
  WriteGoodLights();
  fs::remove(dir_ / "c.png");
  EXPECT_THAT(LoadError(), AllOf(HasSubstr("c.png"), HasSubstr("not found")));
}

TEST_P(LoaderTest, UnreadableImage) {
  WriteGoodLights();
  testing::WriteFile(dir_ / "b.png", "not an image at all");
  EXPECT_THAT(LoadError(), AllOf(HasSubstr("b.png"), HasSubstr("cannot")));
}

TEST_P(LoaderTest, SizeMismatch) {
  WriteGoodLights();
  WriteImages(dir_.path(), {"d.png"}, 7, 4);
  EXPECT_THAT(LoadError(), HasSubstr("d.png is 7x4 but"));
}

TEST_P(LoaderTest, BadLightLine) {
  auto lights = good_lights_;
  lights[2] = "-0.5 abc 0.866";
  WriteLights(lights);
  const std::string error = LoadError();
  EXPECT_THAT(error, HasSubstr(layout_.light_file.string()));
  if (layout_.kind == InputKind::kManifest) {
    EXPECT_THAT(error, HasSubstr("images[2]"));
  } else {
    EXPECT_THAT(error, HasSubstr("line"));
  }
}

TEST_P(LoaderTest, CountMismatch) {
  WriteLights(good_lights_, 5);
  const std::string error = LoadError();
  EXPECT_THAT(error, HasSubstr(layout_.kind == InputKind::kDiligent ? "filenames.txt"
                                                                    : layout_.light_file.string()));
  EXPECT_THAT(error, ::testing::AnyOf(HasSubstr("count 5"), HasSubstr("lists 5 images"),
                                      HasSubstr("2 values")));
}

TEST_P(LoaderTest, ZeroVector) {
  auto lights = good_lights_;
  lights[1] = "0 0 0";
  WriteLights(lights);
  EXPECT_THAT(LoadError(),
              AllOf(HasSubstr(layout_.light_file.string()), HasSubstr("zero-length light vector")));
}

INSTANTIATE_TEST_SUITE_P(AllLayouts, LoaderTest, ::testing::Values(0, 1, 2),
                         [](const auto& param_info) {
                           return std::string(ToString(Layouts()[param_info.param].kind));
                         });

TEST(DetectInputTest, FindsEachLayoutAndRejectsAmbiguity) {
  TempDir dir;
  EXPECT_THROW(DetectInput(dir.path()), Error);
  testing::WriteFile(dir / "a.lp", "x.png 0 0 1\n");
  EXPECT_EQ(DetectInput(dir.path()).kind, InputKind::kLpFile);
  testing::WriteFile(dir / "b.lp", "x.png 0 0 1\n");
  EXPECT_THAT([&] { DetectInput(dir.path()); },
              ::testing::ThrowsMessage<Error>(HasSubstr("several light files (a.lp, b.lp)")));
  EXPECT_EQ(DetectInput(dir / "b.lp").file, dir / "b.lp");
  testing::WriteFile(dir / "light_directions.txt", "0 0 1\n");
  EXPECT_EQ(DetectInput(dir.path()).kind, InputKind::kDiligent);
  testing::WriteFile(dir / "manifest.json", "{}");
  EXPECT_EQ(DetectInput(dir.path()).kind, InputKind::kManifest);
  EXPECT_THROW(DetectInput(dir / "nothing-here"), Error);
}

TEST(LoadDiligentTest, BallLoadsWithMaskIntensitiesAndTruth) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "diligent/ball");
  const LoadedSet loaded = LoadPhotometricSet(folder);
  EXPECT_EQ(loaded.kind, InputKind::kDiligent);
  ASSERT_EQ(loaded.set.size(), 96);
  EXPECT_EQ(loaded.set.width(), 612);
  EXPECT_EQ(loaded.set.height(), 512);
  ASSERT_TRUE(loaded.set.mask());
  EXPECT_EQ(loaded.set.mask()->CountSet(), 15791u);  // the README's count
  EXPECT_TRUE(loaded.set.intensities().empty());     // applied
  ASSERT_TRUE(loaded.ground_truth_normals);
  EXPECT_GT(loaded.saturated_pixels[0], 0u);  // 001.png reaches 65535

  LoadOptions raw;
  raw.apply_intensities = false;
  const LoadedSet unscaled = LoadPhotometricSet(folder, raw);
  ASSERT_EQ(unscaled.set.intensities().size(), 96u);
  // Applied means divided: pick a bright object pixel of image 0.
  const float intensity = unscaled.set.intensities()[0][1];
  EXPECT_NEAR(loaded.set.image(0).at(306, 256, 1),
              unscaled.set.image(0).at(306, 256, 1) / intensity, 1e-6);
}

TEST(LoadLpTest, PtmFitterFixtureDecodesSrgbJpegs) {
  PHOTOMAT_TEST_DATA_OR_SKIP(lp, "ptmfitter/reference_8x5.lp");
  const LoadedSet loaded = LoadPhotometricSet(lp);
  EXPECT_EQ(loaded.set.size(), 12);
  EXPECT_EQ(loaded.set.width(), 8);
  EXPECT_EQ(loaded.set.height(), 5);
  EXPECT_EQ(loaded.set.channels(), 3);
}

// Each image is decoded as its own file says (the value for untagged images does not override a
// tag), and the decisions are recorded for the stack's provenance.
TEST(LoadEncodingTest, EachImageIsDecodedAsItsFileSaysAndRecorded) {
  TempDir dir;
  Image image(4, 3, 3);
  for (float& v : image.values()) v = 0.25f;
  ImageWriteOptions srgb, linear;
  srgb.sample_type = linear.sample_type = SampleType::kUint8;
  srgb.encoding = ColourSpace::kSrgb;      // PNG sRGB chunk
  linear.encoding = ColourSpace::kLinear;  // PNG gAMA 1.0
  WriteImage(dir / "a.png", image, srgb);
  WriteImage(dir / "b.png", image, linear);
  WriteImage(dir / "c.png", image, linear);
  testing::WriteFile(dir / "lights.lp",
                     "3\na.png 0.5 0 0.866\nb.png 0 0.5 0.866\nc.png -0.5 0 0.866\n");
  LoadOptions options;
  options.untagged_colour_space = ColourSpace::kSrgb;
  const LoadedSet loaded = LoadPhotometricSet(dir / "lights.lp", options);
  ASSERT_EQ(loaded.encodings.size(), 3u);
  EXPECT_EQ(loaded.encodings[0].file, "a.png");
  EXPECT_EQ(loaded.encodings[0].encoding, "srgb");
  EXPECT_EQ(loaded.encodings[0].decided_by, "png-srgb");
  EXPECT_EQ(loaded.encodings[1].encoding, "linear");
  EXPECT_EQ(loaded.encodings[1].decided_by, "png-gama");
  // Both decode to the light written, to 8-bit quantisation (half a linear code: 2.0e-3;
  // measured 9.8e-4 linear, 2.0e-4 sRGB). Read with the untagged value (sRGB), b would be 0.05.
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(loaded.set.image(i).at(1, 1, 0), 0.25, 2e-3) << i;
  EXPECT_TRUE(WarnIfEncodingsDisagree(loaded.encodings));
}

// A subset of a streamed set decodes only its images: each band of image j of the subset is the
// set's band of image images[j], bit for bit, with that image's light, name and intensities
// (applied as the set applies them), and the set's mask.
TEST(StreamedSetTest, SubsetReadsItsImagesAsTheSetDoes) {
  TempDir dir;
  const int width = 8, height = 6;
  std::vector<Image> images;
  std::vector<LightDirection> lights;
  std::vector<std::vector<float>> intensities;
  for (int i = 0; i < 5; ++i) {
    Image image(width, height, 3);
    for (std::size_t v = 0; v < image.values().size(); ++v) {
      image.values()[v] =
          static_cast<float>((v * 7 + static_cast<std::size_t>(i) * 13) % 97) / 97.0f;
    }
    images.push_back(std::move(image));
    lights.push_back(LightDirection::FromSlantTilt(0.3 + 0.1 * i, 1.2 * i));
    intensities.push_back({1.0f + 0.1f * i, 0.9f, 1.2f - 0.05f * i});
  }
  PhotometricSet set(std::move(images), lights);
  set.set_intensities(intensities);
  Mask mask(width, height, false);
  for (int y = 1; y < height; ++y) mask.Set(y, y, true);
  set.set_mask(mask);
  SaveSetOptions options;
  options.sample_type = SampleType::kFloat;
  SavePhotometricSet(dir.path() / "capture", set, options);

  StreamedSet whole = OpenStreamedSet(dir.path() / "capture");
  const std::vector<int> chosen = {3, 0};
  StreamedSet subset = whole.Subset(chosen);
  ASSERT_EQ(subset.size(), 2);
  EXPECT_EQ(subset.width(), width);
  EXPECT_TRUE(subset.masked());
  for (int first = 0; first < height; first += 4) {
    const int rows = std::min(4, height - first);
    const PhotometricSet all = whole.ReadBand(rows);
    const PhotometricSet some = subset.ReadBand(rows);
    EXPECT_EQ(subset.next_row(), first + rows);
    for (std::size_t j = 0; j < chosen.size(); ++j) {
      const int i = chosen[j];
      const auto got = some.image(static_cast<int>(j)).values();
      const auto expected = all.image(i).values();
      EXPECT_TRUE(std::equal(got.begin(), got.end(), expected.begin(), expected.end())) << i;
      EXPECT_EQ(some.light(static_cast<int>(j)).vector(), all.light(i).vector()) << i;
      EXPECT_EQ(subset.image_names()[j], whole.image_names()[static_cast<std::size_t>(i)]);
      EXPECT_EQ(subset.intensities()[j], whole.intensities()[static_cast<std::size_t>(i)]);
    }
    EXPECT_EQ(subset.MaskRows(first, rows).CountSet(), whole.MaskRows(first, rows).CountSet());
  }
  const std::vector<int> outside = {5};
  EXPECT_THAT([&] { whole.Subset(outside); },
              ::testing::ThrowsMessage<Error>(HasSubstr("image 5 is not in the set (0 to 4)")));
  EXPECT_THAT([&] { whole.Subset({}); },
              ::testing::ThrowsMessage<Error>(HasSubstr("needs an image")));
}

}  // namespace
}  // namespace photomat

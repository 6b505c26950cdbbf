#include "synthesize/texture/source_map.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

Image Numbered(int width, int height) {
  Image image(width, height, std::vector<std::string>{"a", "b"});
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at(x, y, 0) = static_cast<float>(x);
      image.at(x, y, 1) = static_cast<float>(y);
    }
  }
  return image;
}

SourceMap Mirrored(int width, int height, int sample_width, int sample_height) {
  SourceMap map(width, height, sample_width, sample_height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      map.Set(x, y, {(sample_width - 1 - x % sample_width), y % sample_height});
    }
  }
  return map;
}

TEST(SourceMapTest, ApplyCopiesWholeSamplePixels) {
  const SourceMap map = Mirrored(7, 5, 4, 3);
  ASSERT_TRUE(map.Complete());
  const Image out = map.Apply(Numbered(4, 3));
  EXPECT_EQ(out.channel_names(), (std::vector<std::string>{"a", "b"}));
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 7; ++x) {
      EXPECT_EQ(out.at(x, y, 0), 3 - x % 4);
      EXPECT_EQ(out.at(x, y, 1), y % 3);
    }
  }
}

TEST(SourceMapTest, RejectsOtherSamplesAndIncompleteMaps) {
  EXPECT_THROW(Mirrored(7, 5, 4, 3).Apply(Numbered(5, 3)), Error);
  SourceMap incomplete(2, 2, 4, 3);
  incomplete.Set(0, 0, {1, 1});
  EXPECT_FALSE(incomplete.Complete());
  EXPECT_THROW(incomplete.Apply(Numbered(4, 3)), Error);
  EXPECT_THROW(SourceMap(0, 2, 4, 3), Error);
}

TEST(SourceMapTest, CroppedKeepsTheTopLeft) {
  const SourceMap map = Mirrored(7, 5, 4, 3);
  const SourceMap crop = map.Cropped(3, 2);
  EXPECT_EQ(crop.width(), 3);
  EXPECT_EQ(crop.at(2, 1), map.at(2, 1));
  EXPECT_THROW(map.Cropped(8, 2), Error);
}

TEST(SourceMapTest, SaveAndLoadRoundTripExactly) {
  testing::TempDir dir;
  SourceMap map(300, 2, 70000, 9);  // coordinates beyond 16 bits
  for (int x = 0; x < 300; ++x) {
    map.Set(x, 0, {69999 - x, 8});
    map.Set(x, 1, {x * 17, 0});
  }
  SaveSourceMap(dir / "map.exr", map);
  EXPECT_EQ(LoadSourceMap(dir / "map.exr"), map);
}

TEST(SourceMapTest, LoadRejectsOtherFilesNamingThem) {
  testing::TempDir dir;
  WriteImage(dir / "plain.exr", Numbered(4, 3));
  try {
    LoadSourceMap(dir / "plain.exr");
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_EQ(error.file(), dir / "plain.exr");
    EXPECT_NE(std::string(error.what()).find("not a photomat source map"), std::string::npos);
  }
  // Coordinates outside the sample, or between pixels.
  for (float bad : {4.0f, -1.0f, 1.5f}) {
    Image coordinates(2, 1, std::vector<std::string>{"source.x", "source.y"});
    coordinates.at(0, 0, 0) = bad;
    ImageWriteOptions options;
    options.attributes["photomat:source-map"] =
        R"({"format": "photomat-source-map", "version": 1, "sample_width": 4,
            "sample_height": 3})";
    WriteImage(dir / "bad.exr", coordinates, options);
    EXPECT_THROW(LoadSourceMap(dir / "bad.exr"), Error) << bad;
  }
  EXPECT_THROW(SaveSourceMap(dir / "incomplete.exr", SourceMap(2, 1, 4, 3)), Error);
}

}  // namespace
}  // namespace photomat

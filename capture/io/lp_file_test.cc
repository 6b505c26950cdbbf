#include "capture/io/lp_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;

std::string ErrorOf(const std::string& text) {
  try {
    ParseLpText(text, "lights.lp");
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(LpFileTest, ReadsCountLineAndNormalisesVectors) {
  const auto entries = ParseLpText("2\nimg1.jpg 0 0 2\nimg2.jpg 3 0 4\n", "x.lp");
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0].image, "img1.jpg");
  EXPECT_DOUBLE_EQ(entries[0].light.z(), 1.0);
  EXPECT_DOUBLE_EQ(entries[1].light.x(), 0.6);
  EXPECT_EQ(entries[1].line, 3);
}

TEST(LpFileTest, CountLineIsOptional) {
  EXPECT_EQ(ParseLpText("a.png 0 0 1\nb.png 0 1 1\n", "x.lp").size(), 2u);
}

TEST(LpFileTest, FileNamesMayContainSpacesOrQuotes) {
  const auto entries =
      ParseLpText("2\nmy photo 01.tif 0 0 1\n\"other  photo.tif\" 0 1 1\n", "x.lp");
  EXPECT_EQ(entries[0].image, "my photo 01.tif");
  EXPECT_EQ(entries[1].image, "other  photo.tif");
}

TEST(LpFileTest, AcceptsCrlfBomCommentsBlankLinesAndDecimalCommas) {
  const auto entries =
      ParseLpText("\xEF\xBB\xBF# dome A\r\n2\r\n\r\na.png 0,5 0 0,5\r\nb.png\t0\t0\t1\r\n", "x.lp");
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_NEAR(entries[0].light.x(), std::sqrt(0.5), 1e-15);
  EXPECT_EQ(entries[1].image, "b.png");
}

TEST(LpFileTest, BadNumberNamesLine) {
  EXPECT_THAT(ErrorOf("2\na.png 0 0 1\nb.png 0 x 1\n"),
              HasSubstr("lights.lp: line 3: \"x\" is not a number"));
}

TEST(LpFileTest, TooFewNumbers) {
  EXPECT_THAT(ErrorOf("a.png 0 1\n"), HasSubstr("line 1: expected \"filename x y z\""));
}

TEST(LpFileTest, MissingFileName) {
  EXPECT_THAT(ErrorOf("0.1 0.2 0.9\n"), HasSubstr("line 1: expected \"filename x y z\""));
}

TEST(LpFileTest, ZeroVector) {
  EXPECT_THAT(ErrorOf("a.png 0 0 0\n"), HasSubstr("line 1: zero-length light vector"));
}

TEST(LpFileTest, LightBelowThePlane) {
  EXPECT_THAT(ErrorOf("a.png 0 0.5 -0.5\n"), HasSubstr("light below the sample plane"));
}

TEST(LpFileTest, CountMismatch) {
  EXPECT_THAT(ErrorOf("3\na.png 0 0 1\nb.png 0 1 1\n"),
              HasSubstr("line 1 gives the count 3 but 2 light lines follow"));
}

TEST(LpFileTest, BadCountLine) {
  EXPECT_THAT(ErrorOf("-2\na.png 0 0 1\n"), HasSubstr("line 1: expected the image count"));
  // Beyond the range of an integer (found by tests/fuzz: the conversion was undefined).
  EXPECT_THAT(ErrorOf("33333333333333333333333333\na.png 0 0 1\n"),
              HasSubstr("line 1: expected the image count"));
  EXPECT_THAT(ErrorOf("2.5\na.png 0 0 1\n"), HasSubstr("line 1: expected the image count"));
}

TEST(LpFileTest, EmptyFile) {
  EXPECT_THAT(ErrorOf("12\n"), HasSubstr("no light lines"));
  EXPECT_THAT(ErrorOf(""), HasSubstr("no light lines"));
}

TEST(LpFileTest, MissingFileIsNamed) { EXPECT_THROW(ReadLpFile("/nonexistent/l.lp"), Error); }

TEST(LpFileTest, WriteThenReadRoundTripsExactly) {
  testing::TempDir dir;
  const std::vector<LightDirection> lights = {LightDirection::FromSlantTilt(33.3, 12.1),
                                              LightDirection::FromSlantTilt(60, 300)};
  WriteLpFile(dir / "l.lp", {"a b.png", "c.png"}, lights);
  const auto entries = ReadLpFile(dir / "l.lp");
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0].image, "a b.png");
  for (int i = 0; i < 2; ++i) EXPECT_EQ(entries[i].light.vector(), lights[i].vector());
}

TEST(LpFileTest, ResolvesWindowsPathsByBaseName) {
  testing::TempDir dir;
  testing::WriteFile(dir / "IMG_1.jpg", "x");
  EXPECT_EQ(ResolveImagePath(dir.path(), "C:\\captures\\IMG_1.jpg"), dir / "IMG_1.jpg");
  EXPECT_EQ(ResolveImagePath(dir.path(), "/elsewhere/IMG_1.jpg"), dir / "IMG_1.jpg");
}

TEST(LpFileTest, ReadsThePtmFitterFixture) {
  PHOTOMAT_TEST_DATA_OR_SKIP(file, "ptmfitter/reference_8x5.lp");
  const auto entries = ReadLpFile(file);
  ASSERT_EQ(entries.size(), 12u);
  EXPECT_EQ(entries[0].image, "IMG_0000.jpg");
  EXPECT_NEAR(entries[0].light.z(), 0.08715574274765814, 1e-15);
}

}  // namespace
}  // namespace photomat

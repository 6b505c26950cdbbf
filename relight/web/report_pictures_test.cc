#include "relight/web/report_pictures.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

TEST(ReportPicturesTest, TheFactorBringsTheLongerSideWithinTheDisplaySide) {
  EXPECT_EQ(ReportDisplayFactor(612, 512), 1);
  EXPECT_EQ(ReportDisplayFactor(1024, 1024), 1);
  EXPECT_EQ(ReportDisplayFactor(1025, 10), 2);
  EXPECT_EQ(ReportDisplayFactor(4096, 3072), 4);
  EXPECT_EQ(ReportDisplayFactor(8688, 5792), 9);  // 48 MP: 966 x 644
}

// A 5 x 4 picture by 2: blocks of 2 x 2, 1 x 2, 2 x 1 and 1 x 1 at the edges, each the mean of
// its pixels (values x + 10 y).
TEST(ReportPicturesTest, EachDisplayPixelIsTheMeanOfItsBlock) {
  Image picture(5, 3, 1);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) picture.at(x, y, 0) = static_cast<float>(x + 10 * y);
  }
  DisplayReduction reduction(5, 3, 1, 2);
  reduction.Add(0, picture.View());
  const Image out = reduction.Result();
  ASSERT_EQ(out.width(), 3);
  ASSERT_EQ(out.height(), 2);
  EXPECT_FLOAT_EQ(out.at(0, 0, 0), 5.5f);   // (0 + 1 + 10 + 11) / 4
  EXPECT_FLOAT_EQ(out.at(2, 0, 0), 9.0f);   // (4 + 14) / 2
  EXPECT_FLOAT_EQ(out.at(1, 1, 0), 22.5f);  // (22 + 23) / 2
  EXPECT_FLOAT_EQ(out.at(2, 1, 0), 24.0f);
}

// Bands of any height, given in row order, make the same picture bit for bit; negative values
// are left out when asked, and a block of only those reads -1.
TEST(ReportPicturesTest, BandsMakeTheOneBandPictureAndUndefinedValuesAreLeftOut) {
  Image picture(37, 29, 2);
  for (std::size_t i = 0; i < picture.values().size(); ++i) {
    picture.values()[i] = static_cast<float>((i * 7919) % 1000) / 997.0f - 0.1f;
  }
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 3; ++x) picture.at(x, y, 1) = -1.0f;
  }
  DisplayReduction whole(37, 29, 2, 3, true);
  whole.Add(0, picture.View());
  const Image expected = whole.Result();
  EXPECT_FLOAT_EQ(expected.at(0, 0, 1), -1.0f);
  for (int rows : {1, 2, 5}) {
    DisplayReduction banded(37, 29, 2, 3, true);
    for (int first = 0; first < 29; first += rows) {
      banded.Add(first, picture.Rows(first, std::min(rows, 29 - first)));
    }
    EXPECT_TRUE(testing::SameBits(banded.Result(), expected)) << rows;
  }
  // Block (1, 0) of channel 1 with one undefined pixel: skipped, the mean of the other 8; not
  // skipped, the mean of all 9.
  picture.at(4, 1, 1) = -1.0f;
  double others = 0.0;
  for (int y = 0; y < 3; ++y) {
    for (int x = 3; x < 6; ++x) others += (x == 4 && y == 1) ? 0.0 : picture.at(x, y, 1);
  }
  DisplayReduction skipping(37, 29, 2, 3, true), all(37, 29, 2, 3);
  skipping.Add(0, picture.View());
  all.Add(0, picture.View());
  EXPECT_NEAR(skipping.Result().at(1, 0, 1), others / 8, 1e-6);
  EXPECT_NEAR(all.Result().at(1, 0, 1), (others - 1.0) / 9, 1e-6);
  EXPECT_THROW(all.Add(28, picture.Rows(0, 2)), Error);  // past the last row
  EXPECT_THROW(all.Add(0, picture.Rows(0, 1)), Error);   // a row added twice
}

// Rows never added count as zeros: the picture of a band of values and zero rows elsewhere.
TEST(ReportPicturesTest, MissingRowsCountAsZero) {
  Image picture(8, 7, 1);
  for (std::size_t i = 0; i < picture.values().size(); ++i) {
    picture.values()[i] = 1.0f + static_cast<float>(i % 5);
  }
  Image zeroed = picture;
  for (int y = 0; y < 7; ++y) {
    for (int x = 0; x < 8; ++x) {
      if (y < 2 || y > 4) zeroed.at(x, y, 0) = 0.0f;
    }
  }
  DisplayReduction whole(8, 7, 1, 3);
  whole.Add(0, zeroed.View());
  DisplayReduction part(8, 7, 1, 3);
  EXPECT_FALSE(part.has_rows());
  part.Add(2, picture.Rows(2, 3));
  EXPECT_TRUE(part.has_rows());
  part.CountMissingRowsAsZero();
  EXPECT_TRUE(testing::SameBits(part.Result(), whole.Result()));
}

}  // namespace
}  // namespace photomat

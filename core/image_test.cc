#include "core/image.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <vector>

#include "core/error.h"

namespace photomat {
namespace {

// Value 1000 c + 100 z + 10 y + x at (x, y, z, c): every voxel says where it is.
Image NumberedImage(ImageExtent extent, int channels) {
  Image image(extent, channels);
  for (int c = 0; c < channels; ++c) {
    for (int z = 0; z < extent.depth; ++z) {
      for (int y = 0; y < extent.height; ++y) {
        for (int x = 0; x < extent.width; ++x) {
          image.at(x, y, z, c) = static_cast<float>(1000 * c + 100 * z + 10 * y + x);
        }
      }
    }
  }
  return image;
}

TEST(ImageTest, StorageIsPlanarWithRowsContiguous) {
  const Image image = NumberedImage({4, 3, 2}, 2);
  ASSERT_EQ(image.pixel_count(), 24u);
  ASSERT_EQ(image.values().size(), 48u);
  // Plane c is width * height * depth values, x fastest, then y, then z.
  for (int c = 0; c < 2; ++c) {
    const std::span<const float> plane = image.plane(c);
    ASSERT_EQ(plane.data(), image.values().data() + c * 24);
    EXPECT_EQ(plane[0], 1000.0f * c);
    EXPECT_EQ(plane[1], 1000.0f * c + 1);     // x + 1
    EXPECT_EQ(plane[4], 1000.0f * c + 10);    // y + 1
    EXPECT_EQ(plane[12], 1000.0f * c + 100);  // z + 1
  }
  EXPECT_EQ(image.row(1, 2, 1)[3], 1000 + 100 + 20 + 3);
  EXPECT_EQ(image.Index(3, 2, 1), 23u);
}

TEST(ImageTest, PixelValuesReachEveryPlane) {
  Image image = NumberedImage({3, 2, 1}, 3);
  const PixelValues<float> pixel = image.pixel(2, 1);
  ASSERT_EQ(pixel.size(), 3u);
  EXPECT_EQ(std::vector<float>(pixel.begin(), pixel.end()),
            (std::vector<float>{12.0f, 1012.0f, 2012.0f}));
  pixel[1] = -1.0f;
  EXPECT_EQ(image.at(2, 1, 1), -1.0f);
  // Linear index, read-only conversion, standard algorithms over the strided iterators.
  const PixelValues<const float> same = image.pixel(std::size_t{5});
  EXPECT_EQ(same[2], 2012.0f);
  EXPECT_EQ(std::accumulate(same.begin(), same.end(), 0.0f), 12.0f - 1.0f + 2012.0f);
  EXPECT_EQ(same.end() - same.begin(), 3);
  std::vector<float> out(3);
  std::copy(same.begin(), same.end(), out.begin());
  std::copy(out.rbegin(), out.rend(), image.pixel(0, 0).begin());
  EXPECT_EQ(image.at(0, 0, 0), 2012.0f);
  EXPECT_EQ(image.at(0, 0, 2), 12.0f);
}

TEST(ImageTest, ViewsSelectRowsAndChannelsWithoutCopies) {
  Image image = NumberedImage({5, 4, 1}, 3);
  const ConstImageView band = image.Rows(1, 2);
  EXPECT_EQ(band.width(), 5);
  EXPECT_EQ(band.height(), 2);
  EXPECT_EQ(band.channels(), 3);
  EXPECT_EQ(band.at(4, 1, 2), 2000 + 20 + 4);  // row 1 of the band is image row 2
  EXPECT_EQ(band.row(0, 0).data(), image.row(0, 1).data());
  const ConstImageView colour = image.ChannelRange(1, 2).Rows(3, 1);
  EXPECT_EQ(colour.channels(), 2);
  EXPECT_EQ(colour.at(0, 0, 0), 1030.0f);
  EXPECT_EQ(colour.pixel(2, 0)[1], 2032.0f);
  // A writable view writes through.
  image.ChannelRange(2, 1).at(1, 1, 0) = -5.0f;
  EXPECT_EQ(image.at(1, 1, 2), -5.0f);
  EXPECT_THROW(image.Rows(3, 2), Error);
  EXPECT_THROW(image.ChannelRange(-1, 2), Error);
  EXPECT_THROW(image.View().ChannelRange(2, 2), Error);
}

TEST(ImageTest, VolumeSlicesAreViewsWithUnitXStride) {
  Image volume = NumberedImage({4, 3, 5}, 2);
  const ConstImageView xy = volume.SliceXY(3);
  EXPECT_EQ(xy.width(), 4);
  EXPECT_EQ(xy.height(), 3);
  EXPECT_EQ(xy.at(2, 1, 1), 1000 + 300 + 10 + 2);
  const ConstImageView xz = volume.SliceXZ(2);
  EXPECT_EQ(xz.width(), 4);
  EXPECT_EQ(xz.height(), 5);
  EXPECT_EQ(xz.row_stride(), 12);
  EXPECT_EQ(xz.at(3, 4, 0), 400 + 20 + 3);  // row = z
  volume.SliceXZ(0).at(1, 2, 1) = 7.0f;
  EXPECT_EQ(volume.at(1, 0, 2, 1), 7.0f);
  EXPECT_THROW(volume.SliceXY(5), Error);
  EXPECT_THROW(volume.SliceXZ(-1), Error);
  // A copy of a view holds its pixels.
  const Image copy(volume.SliceXZ(1).ChannelRange(1, 1));
  EXPECT_EQ(copy.width(), 4);
  EXPECT_EQ(copy.height(), 5);
  EXPECT_EQ(copy.channels(), 1);
  EXPECT_EQ(copy.at(2, 3, 0), 1000 + 300 + 10 + 2);
}

TEST(ImageTest, CopyPixelsCopiesBandsAndChecksShapes) {
  const Image from = NumberedImage({3, 3, 1}, 2);
  Image to(3, 5, 2);
  CopyPixels(from.Rows(1, 2), to.Rows(3, 2));
  for (int c = 0; c < 2; ++c) {
    for (int x = 0; x < 3; ++x) {
      EXPECT_EQ(to.at(x, 3, c), from.at(x, 1, c));
      EXPECT_EQ(to.at(x, 4, c), from.at(x, 2, c));
      EXPECT_EQ(to.at(x, 0, c), 0.0f);
    }
  }
  Image wide(5, 3, 2);
  EXPECT_THROW(CopyPixels(from, wide.View()), Error);
  EXPECT_THROW(CopyPixels(from, to.View()), Error);
}

TEST(ImageTest, ChannelsAndNames) {
  Image image(2, 2, std::vector<std::string>{"a", "b", "c"});
  image.at(1, 1, 2) = 3.0f;
  const Image last = image.Channels(1, 2);
  EXPECT_EQ(last.channel_names(), (std::vector<std::string>{"b", "c"}));
  EXPECT_EQ(last.at(1, 1, 1), 3.0f);
  EXPECT_EQ(image.FindChannel("c"), 2);
  EXPECT_EQ(image.FindChannel("d"), -1);
  EXPECT_THROW(image.set_channel_names({"x"}), Error);
  image.set_channel_names({});  // no names is allowed
  EXPECT_TRUE(image.channel_names().empty());
  EXPECT_THROW(image.Channels(2, 2), Error);
}

TEST(ImageTest, ShapesAreChecked) {
  EXPECT_THROW(Image(-1, 2, 1), Error);
  EXPECT_NO_THROW(Image(0, 0, 3));  // an empty picture
  EXPECT_THROW(Image(ImageExtent{0, 1, 1}, 1), Error);
  EXPECT_THROW(Image(ImageExtent{1, 1, 1}, 0), Error);
  EXPECT_THROW(Image(ImageExtent{65536, 65536, 2}, 1), Error);
  EXPECT_EQ(ToString(ImageExtent{8, 16, 4}), "8x16x4");
  EXPECT_EQ(ImageExtent::Cube(3).pixel_count(), 27u);
}

}  // namespace
}  // namespace photomat

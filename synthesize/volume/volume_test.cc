#include "synthesize/volume/volume.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <cmath>

#include "core/error.h"
#include "core/image_io.h"
#include "synthesize/volume/volume_filter.h"
#include "synthesize/volume/volume_io.h"
#include "synthesize/volume/voxel_hash.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using testing::TempDir;

Image NumberedVolume(ImageExtent size, int channels) {
  Image volume(size, channels);
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        for (int c = 0; c < channels; ++c)
          volume.at(x, y, z, c) = x + 100 * y + 10000 * z + 0.25f * c;
      }
    }
  }
  return volume;
}

Image RandomVolume(ImageExtent size, std::vector<std::string> names, std::uint64_t seed) {
  Image volume(size, std::move(names));
  for (std::size_t i = 0; i < volume.values().size(); ++i) {
    volume.values()[i] = HashToSigned(HashVoxel(seed, 0, static_cast<std::int64_t>(i), 0, 0)) * 3;
  }
  return volume;
}

void ExpectSameVolume(const Image& a, const Image& b) {
  ASSERT_TRUE(a.SameShape(b));
  EXPECT_EQ(a.channel_names(), b.channel_names());
  for (std::size_t i = 0; i < a.values().size(); ++i) {
    ASSERT_EQ(a.values()[i], b.values()[i]) << "value " << i;
  }
}

TEST(VolumeTest, ParsesSizes) {
  EXPECT_EQ(ParseVolumeSize("64"), ImageExtent::Cube(64));
  EXPECT_EQ(ParseVolumeSize("8x16x4"), (ImageExtent{8, 16, 4}));
  EXPECT_FALSE(ParseVolumeSize("8x16"));
  EXPECT_FALSE(ParseVolumeSize("0"));
  EXPECT_FALSE(ParseVolumeSize("8x-1x2"));
  EXPECT_FALSE(ParseVolumeSize("abc"));
  EXPECT_THROW(Image(ImageExtent{0, 1, 1}, 1), Error);
  EXPECT_THROW(Image(ImageExtent{1, 1, 1}, 0), Error);
}

TEST(VolumeTest, SlicesFollowTheFixedAxes) {
  const Image volume = NumberedVolume({5, 4, 3}, 2);
  const Image xy = ExtractSlice(volume, SlicePlane::kXY, 2);
  EXPECT_EQ(xy.width(), 5);
  EXPECT_EQ(xy.height(), 4);
  EXPECT_EQ(xy.at(3, 1, 1), 3 + 100 * 1 + 10000 * 2 + 0.25f);
  const Image xz = ExtractSlice(volume, SlicePlane::kXZ, 1);
  EXPECT_EQ(xz.width(), 5);
  EXPECT_EQ(xz.height(), 3);
  EXPECT_EQ(xz.at(4, 2, 0), 4 + 100 * 1 + 10000 * 2);
  const Image yz = ExtractSlice(volume, SlicePlane::kYZ, 0);
  EXPECT_EQ(yz.width(), 4);
  EXPECT_EQ(yz.height(), 3);
  EXPECT_EQ(yz.at(3, 1, 0), 0 + 100 * 3 + 10000 * 1);
  EXPECT_THROW(ExtractSlice(volume, SlicePlane::kXY, 3), Error);

  Image copy(volume.extent(), 2);
  for (SlicePlane plane : kAllSlicePlanes) {
    Image rebuilt(volume.extent(), 2);
    for (int i = 0; i < SliceCount(volume.extent(), plane); ++i) {
      InsertSlice(rebuilt, plane, i, ExtractSlice(volume, plane, i));
    }
    ExpectSameVolume(rebuilt, volume);
  }
  EXPECT_THROW(InsertSlice(copy, SlicePlane::kXY, 0, Image(4, 4, 2)), Error);
}

TEST(VolumeFilterTest, GaussianBlurKeepsTheMeanAndSmoothsAnImpulse) {
  Image impulse(ImageExtent{12, 10, 8}, 2);
  impulse.at(0, 5, 4, 0) = 1.0f;  // on a face: wraps or piles up at the edge
  impulse.at(6, 5, 4, 1) = 1.0f;
  const Image wrapped = GaussianBlur(impulse, 1.0, VolumeEdge::kWrap);
  double sum = 0;
  for (std::size_t i = 0; i < wrapped.pixel_count(); ++i) sum += wrapped.pixel(i)[0];
  EXPECT_NEAR(sum, 1.0, 1e-5);
  EXPECT_NEAR(wrapped.at(11, 5, 4, 0), wrapped.at(1, 5, 4, 0), 1e-7);  // symmetric across the wrap
  // One voxel away along one axis: exp(-1/2) of the centre.
  EXPECT_NEAR(wrapped.at(7, 5, 4, 1) / wrapped.at(6, 5, 4, 1), std::exp(-0.5), 1e-5);
  const Image clamped = GaussianBlur(impulse, 1.0, VolumeEdge::kClamp);
  EXPECT_EQ(clamped.at(11, 5, 4, 0), 0.0f);
  EXPECT_GT(clamped.at(0, 5, 4, 0), wrapped.at(0, 5, 4, 0));  // the cut-off tail folds back
  EXPECT_EQ(GaussianBlur(impulse, 0.0, VolumeEdge::kWrap).values()[0], impulse.values()[0]);
  // The binomial pyramid's blur: 1 voxel at spacing 2, sqrt(5) at 4.
  EXPECT_EQ(GaussianStackSigma(1), 0.0);
  EXPECT_NEAR(GaussianStackSigma(2), 1.0, 1e-12);
  EXPECT_NEAR(GaussianStackSigma(4), std::sqrt(5.0), 1e-12);
}

TEST(VolumeIoTest, OpenVdbRoundTripIsExact) {
  TempDir dir;
  const Image volume = RandomVolume({7, 5, 3}, {"normal.X", "normal.Y", "normal.Z", "a", "b"}, 3);
  WriteVolume(dir / "v.vdb", volume);
  ExpectSameVolume(ReadVolume(dir / "v.vdb"), volume);

  // A colour volume also carries Blender's grids, which reading skips.
  const Image colour = RandomVolume({6, 6, 6}, {"R", "G", "B"}, 4);
  WriteVolumeVdb(dir / "c.vdb", colour);
  ExpectSameVolume(ReadVolumeVdb(dir / "c.vdb"), colour);
  openvdb::io::File file((dir / "c.vdb").string());
  file.open();
  EXPECT_TRUE(file.hasGrid("color"));
  EXPECT_TRUE(file.hasGrid("density"));
  file.close();
}

TEST(VolumeIoTest, ReadsAVdbWrittenElsewhere) {
  TempDir dir;
  openvdb::initialize();
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("smoke");
  auto accessor = grid->getAccessor();
  accessor.setValue(openvdb::Coord(10, 20, 30), 2.0f);
  accessor.setValue(openvdb::Coord(12, 21, 30), 3.0f);
  openvdb::io::File file((dir / "foreign.vdb").string());
  file.write({grid});
  file.close();
  const Image volume = ReadVolumeVdb(dir / "foreign.vdb");
  EXPECT_EQ(volume.extent(), (ImageExtent{3, 2, 1}));
  EXPECT_EQ(volume.channel_names(), std::vector<std::string>{"smoke"});
  EXPECT_EQ(volume.at(0, 0, 0, 0), 2.0f);
  EXPECT_EQ(volume.at(2, 1, 0, 0), 3.0f);
  EXPECT_EQ(volume.at(1, 0, 0, 0), 0.0f);
}

TEST(VolumeIoTest, ExrSliceStackRoundTripIsExact) {
  TempDir dir;
  const Image volume = RandomVolume({9, 4, 5}, {"R", "G", "B", "height"}, 5);
  WriteVolume(dir / "stack", volume);
  EXPECT_TRUE(std::filesystem::exists(dir / "stack" / "slice_0004.exr"));
  ExpectSameVolume(ReadVolume(dir / "stack"), volume);
}

TEST(VolumeIoTest, BadFilesAreErrorsNamingThem) {
  TempDir dir;
  testing::WriteFile(dir / "text.vdb", "this is not a volume\n");
  try {
    ReadVolume(dir / "text.vdb");
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.file(), dir / "text.vdb");
  }
  EXPECT_THROW(ReadVolume(dir / "missing.vdb"), Error);
  EXPECT_THROW(ReadVolume(dir / "no-stack"), Error);

  const Image volume = RandomVolume({4, 4, 3}, {"R", "G", "B"}, 6);
  WriteVolume(dir / "stack", volume);
  std::filesystem::remove(dir / "stack" / "slice_0001.exr");
  EXPECT_THROW(ReadVolume(dir / "stack"), Error);
  testing::WriteFile(dir / "stack" / "slice_0001.exr", "junk");
  EXPECT_THROW(ReadVolume(dir / "stack"), Error);

  // A slice of the wrong size.
  WriteVolume(dir / "stack2", volume);
  WriteImage(dir / "stack2" / "slice_0002.exr", Image(5, 4, 3));
  try {
    ReadVolume(dir / "stack2");
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.file(), dir / "stack2" / "slice_0002.exr");
  }
  Image duplicate(ImageExtent::Cube(2), std::vector<std::string>{"a", "a"});
  EXPECT_THROW(WriteVolume(dir / "dup.vdb", duplicate), Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "dup.vdb"));
}

TEST(VolumeIoTest, WritesCentralSlicePictures) {
  TempDir dir;
  Image volume(ImageExtent{8, 6, 4}, std::vector<std::string>{"R", "G", "B"});
  for (int z = 0; z < 4; ++z) {
    for (int y = 0; y < 6; ++y) {
      for (int x = 0; x < 8; ++x) volume.at(x, y, z, 0) = x / 7.0f;
    }
  }
  const auto paths = WriteCentralSlices(dir / "slices", "solid_", volume);
  ASSERT_EQ(paths.size(), 3u);
  const Image xz = ReadImage(dir / "slices" / "solid_xz.png").image;
  EXPECT_EQ(xz.width(), 8);
  EXPECT_EQ(xz.height(), 4);
  EXPECT_NEAR(xz.at(7, 0, 0), 1.0f, 1e-6);
  EXPECT_NEAR(xz.at(0, 0, 0), 0.0f, 1e-6);
  const Image yz = ReadImage(dir / "slices" / "solid_yz.png").image;
  EXPECT_EQ(yz.width(), 6);
  EXPECT_NEAR(yz.at(0, 0, 0), 4 / 7.0f, 0.01);  // x = 4, the centre
}

}  // namespace
}  // namespace photomat

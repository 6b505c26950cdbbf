#include "core/disk_space.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/image.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(DiskSpaceTest, EstimateBoundsTheFilesPhotomatWrites) {
  testing::TempDir dir;
  // Noise is the worst case of every compression: the estimate must still hold the file.
  Image noise(300, 200, 3);
  std::uint32_t state = 12345;  // a fixed linear congruential sequence: the same noise every run
  for (float& v : noise.values()) {
    state = state * 1664525u + 1013904223u;
    v = static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
  }
  ImageWriteOptions png8, png16, exr;
  png8.sample_type = SampleType::kUint8;
  png16.sample_type = SampleType::kUint16;
  WriteImage(dir / "a.png", noise, png8);
  WriteImage(dir / "b.png", noise, png16);
  WriteImage(dir / "c.exr", noise, exr);
  EXPECT_LE(std::filesystem::file_size(dir / "a.png"), ImageFileBytes(300, 200, 3, 1));
  EXPECT_LE(std::filesystem::file_size(dir / "b.png"), ImageFileBytes(300, 200, 3, 2));
  EXPECT_LE(std::filesystem::file_size(dir / "c.exr"), ImageFileBytes(300, 200, 3, 4));
  // And it is not wildly above them: at most the 1 % margin and the fixed overhead.
  EXPECT_GE(
      std::filesystem::file_size(dir / "c.exr") + 300 * 200 * 3 * 4 / 100 + kImageFileOverhead,
      ImageFileBytes(300, 200, 3, 4));
}

TEST(DiskSpaceTest, TooLittleSpaceIsAnErrorNamingTheFolderAndTheFigures) {
  testing::TempDir dir;
  EXPECT_NO_THROW(CheckDiskSpace(dir.path(), 5u << 20, "relit images", std::size_t{6} << 20));
  EXPECT_THAT(
      [&] { CheckDiskSpace(dir.path(), (std::size_t{5} << 20) + 1, "relit images", 3u << 20); },
      ThrowsMessage<Error>(HasSubstr(dir.path().string() +
                                     ": not enough disk space for relit images: 6 MB needed here, "
                                     "3 MB free")));
}

TEST(DiskSpaceTest, FreeSpaceOfAFolderNotMadeYetIsItsParentsFileSystems) {
  testing::TempDir dir;
  const std::size_t here = AvailableDiskBytes(dir.path());
  EXPECT_GT(here, 0u);
  // The same file system: equal within what other processes write meanwhile (64 MiB).
  const std::size_t later = AvailableDiskBytes(dir / "not/made/yet");
  EXPECT_LT(later > here ? later - here : here - later, std::size_t{64} << 20);
  // The real check passes for a tiny need.
  EXPECT_NO_THROW(CheckDiskSpace(dir / "out", 1, "a test"));
}

}  // namespace
}  // namespace photomat

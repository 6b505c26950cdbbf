#include "core/jpeg_structure.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

using ::testing::HasSubstr;
using ::testing::Optional;
using testing::TempDir;

// A 96 x 64 RGB JPEG of a noisy gradient (so that its compressed data holds many FF bytes),
// baseline or progressive; returns the file's bytes.
std::string WriteJpeg(const fs::path& path, bool progressive) {
  OIIO::ImageSpec spec(96, 64, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", "jpeg:95");
  if (progressive) spec.attribute("jpeg:progressive", 1);
  std::vector<unsigned char> pixels(96 * 64 * 3);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    pixels[i] = static_cast<unsigned char>((i * 7919 + (i / 3) % 96 * 2) % 256);
  }
  auto output = OIIO::ImageOutput::create(path.string());
  EXPECT_TRUE(output && output->open(path.string(), spec));
  EXPECT_TRUE(output->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
  EXPECT_TRUE(output->close());
  return ReadTextFile(path);  // binary: the bytes as stored
}

TEST(JpegStructureTest, ACompleteFileHasNoFault) {
  TempDir dir;
  for (const bool progressive : {false, true}) {
    const fs::path path = dir / (progressive ? "progressive.jpg" : "baseline.jpg");
    const std::string bytes = WriteJpeg(path, progressive);
    ASSERT_GT(bytes.size(), 1000u);
    EXPECT_EQ(FindJpegTruncation(path), std::nullopt) << path;
  }
}

// Cut at every 97th byte from the end of the headers on (and one and two bytes short of the
// whole, which removes the end-of-image marker): every cut is found. Progressive files hold
// several scans, so the cuts fall in scans other than the first too.
TEST(JpegStructureTest, EveryCutIsFound) {
  TempDir dir;
  for (const bool progressive : {false, true}) {
    const std::string bytes = WriteJpeg(dir / "whole.jpg", progressive);
    std::vector<std::size_t> cuts = {bytes.size() - 1, bytes.size() - 2};
    for (std::size_t cut = 700; cut < bytes.size() - 2; cut += 97) cuts.push_back(cut);
    int later_scans = 0;
    for (const std::size_t cut : cuts) {
      testing::WriteFile(dir / "cut.jpg", bytes.substr(0, cut));
      const std::optional<std::string> fault = FindJpegTruncation(dir / "cut.jpg");
      ASSERT_TRUE(fault.has_value()) << "cut at " << cut << " of " << bytes.size();
      EXPECT_THAT(*fault, HasSubstr("it is cut short"));
      EXPECT_THAT(*fault, HasSubstr(fmt::format("ends at byte {}", cut)));
      if (fault->find("scan 1,") == std::string::npos) ++later_scans;
    }
    if (progressive) {
      EXPECT_GT(later_scans, 0);
    }
  }
}

// Cameras may append data after the image (a motion photo's video); the primary image is whole,
// so the file passes, and cut inside the image it does not.
TEST(JpegStructureTest, DataAfterTheImageIsAllowed) {
  TempDir dir;
  const std::string bytes = WriteJpeg(dir / "whole.jpg", false);
  const std::string appended(200000, '\x42');
  testing::WriteFile(dir / "motion.jpg", bytes + appended);
  EXPECT_EQ(FindJpegTruncation(dir / "motion.jpg"), std::nullopt);
  testing::WriteFile(dir / "cut.jpg", bytes.substr(0, bytes.size() / 2));
  EXPECT_THAT(FindJpegTruncation(dir / "cut.jpg"),
              Optional(HasSubstr("inside the compressed data of scan 1")));
}

TEST(JpegStructureTest, NotAJpegAndAMissingFile) {
  TempDir dir;
  testing::WriteFile(dir / "text.jpg", "hello, world");
  EXPECT_THAT(FindJpegTruncation(dir / "text.jpg"), Optional(HasSubstr("start-of-image")));
  EXPECT_THROW(FindJpegTruncation(dir / "missing.jpg"), Error);
}

}  // namespace
}  // namespace photomat

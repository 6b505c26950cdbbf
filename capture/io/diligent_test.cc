#include "capture/io/diligent.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

class DiligentFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    testing::WriteFile(dir_ / "filenames.txt", "001.png\n002.png\n");
    testing::WriteFile(dir_ / "001.png", "");
    testing::WriteFile(dir_ / "002.png", "");
    testing::WriteFile(dir_ / "light_directions.txt", "0 0 1\n0.1 0.2 0.9\n");
  }
  testing::TempDir dir_;
};

TEST_F(DiligentFilesTest, IntensitiesAreOptional) {
  const DiligentFiles files = ReadDiligentFiles(dir_.path());
  EXPECT_EQ(files.images.size(), 2u);
  EXPECT_TRUE(files.intensities.empty());
  EXPECT_FALSE(files.mask);
}

TEST_F(DiligentFilesTest, RowWithTwoNumbersNamesFileAndLine) {
  testing::WriteFile(dir_ / "light_intensities.txt", "1 1 1\n1 1\n");
  EXPECT_THAT([&] { ReadDiligentFiles(dir_.path()); },
              ThrowsMessage<Error>(HasSubstr("light_intensities.txt: line 2: expected 3 numbers")));
}

TEST_F(DiligentFilesTest, NonPositiveIntensityIsRejected) {
  testing::WriteFile(dir_ / "light_intensities.txt", "1 1 1\n1 0 1\n");
  EXPECT_THAT([&] { ReadDiligentFiles(dir_.path()); },
              ThrowsMessage<Error>(HasSubstr("line 2: intensities must be positive")));
}

TEST_F(DiligentFilesTest, MissingNamesFileIsNamed) {
  std::filesystem::remove(dir_ / "filenames.txt");
  EXPECT_THAT([&] { ReadDiligentFiles(dir_.path()); },
              ThrowsMessage<Error>(HasSubstr("filenames.txt: file not found")));
}

}  // namespace
}  // namespace photomat

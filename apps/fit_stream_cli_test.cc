// `photomat fit` streams (README, "Streamed fitting"): these run the built executable.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/image_io.h"
#include "represent/stack/map_stack.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

ImageWriteOptions Uint16() {
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint16;
  return options;
}
using ::testing::HasSubstr;
using testing::RunPhotomat;
using testing::RunResult;
using testing::TempDir;

std::size_t FilesIn(const fs::path& folder) {
  std::size_t count = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(folder)) ++count;
  return count;
}

TEST(FitStreamCliTest, ImageOfAnotherSizeFailsNamingItAndLeavesNoOutput) {
  const TempDir dir;
  const std::string capture = (dir / "capture").string();
  ASSERT_EQ(RunPhotomat("generate --out " + capture + " --size 40x32 --seed 5").exit_code, 0);
  WriteImage(dir / "capture" / "img_007.png", Image(40, 31, 3), Uint16());
  const RunResult fit =
      RunPhotomat("fit " + capture + " --method all --out " + (dir / "out").string());
  EXPECT_NE(fit.exit_code, 0);
  EXPECT_THAT(fit.output, HasSubstr("img_007.png is 40x31 but"));
  EXPECT_FALSE(fs::exists(dir / "out") && FilesIn(dir / "out") > 0);
}

TEST(FitStreamCliTest, ImageTruncatedMidwayFailsNamingItAndLeavesNoOutput) {
  const TempDir dir;
  const std::string capture = (dir / "capture").string();
  ASSERT_EQ(RunPhotomat("generate --out " + capture + " --size 64x256 --seed 6").exit_code, 0);
  const fs::path victim = dir / "capture" / "img_030.png";
  fs::resize_file(victim, fs::file_size(victim) / 2);
  const RunResult fit = RunPhotomat("fit " + capture + " --method all --robust --memory 1 --out " +
                                    (dir / "out").string());
  EXPECT_NE(fit.exit_code, 0);
  EXPECT_THAT(fit.output, HasSubstr("img_030.png"));
  ASSERT_TRUE(fs::exists(dir / "out"));
  EXPECT_EQ(FilesIn(dir / "out"), 0u) << fit.output;
}

}  // namespace
}  // namespace photomat

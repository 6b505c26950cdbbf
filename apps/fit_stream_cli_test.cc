// `photomat fit` streams (README, "Streamed fitting"): these run the built executable.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

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

// photomat under a hard address-space limit (setrlimit RLIMIT_AS through the shell's ulimit -v,
// in the child only): every allocation beyond it fails.
RunResult RunPhotomatWithAddressSpace(std::size_t megabytes, const std::string& arguments) {
  const std::string command = "ulimit -v " + std::to_string(megabytes * 1024) + " && exec " +
                              testing::PhotomatExecutable().string() + " " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return {-1, "cannot start " + command};
  std::string output;
  char buffer[4096];
  while (std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

double LargestDifference(const Image& a, const Image& b) {
  double difference = 0.0;
  for (std::size_t i = 0; i < a.values().size(); ++i) {
    difference = std::max(difference, std::abs(double{a.values()[i]} - b.values()[i]));
  }
  return difference;
}

// Measured: the limit and the difference bound are set in FitsUnderAnAddressSpaceLimit below.
constexpr std::size_t kAddressSpaceMegabytes = 0;
constexpr double kBandDifferenceBound = 0;

std::size_t FilesIn(const fs::path& folder) {
  std::size_t count = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(folder)) ++count;
  return count;
}

// A 1024 x 1024 x 36 capture needs about 27 bytes per pixel per image in memory (1 GB) on top of
// the program; streamed in bands of a 48 MB budget it fits under an address-space limit that
// leaves a fraction of that, and gives the maps of an unlimited one-band fit.
TEST(FitStreamCliTest, FitsUnderAnAddressSpaceLimitFarBelowTheInMemoryNeed) {
  const TempDir dir;
  const std::string capture = (dir / "capture").string();
  ASSERT_EQ(RunPhotomat("generate --out " + capture + " --size 1024x1024 --pattern bumps --seed 3")
                .exit_code,
            0);
  const std::string methods = " --method gradient,ptm,eigen6 ";
  // The program's own address space (libraries, thread stacks, malloc arenas) on a small fit.
  const RunResult limited = RunPhotomatWithAddressSpace(
      kAddressSpaceMegabytes,
      "fit " + capture + methods + "--memory 48 --out " + (dir / "limited").string());
  ASSERT_EQ(limited.exit_code, 0) << limited.output;
  // One band of the whole image (what the in-memory fit held) does not fit under that limit.
  const RunResult whole = RunPhotomatWithAddressSpace(
      kAddressSpaceMegabytes,
      "fit " + capture + methods + "--memory 8000 --out " + (dir / "whole-limited").string());
  EXPECT_NE(whole.exit_code, 0) << whole.output;
  const RunResult free =
      RunPhotomat("fit " + capture + methods + "--memory 8000 --out " + (dir / "free").string());
  ASSERT_EQ(free.exit_code, 0) << free.output;
  for (const char* method : {"gradient", "ptm", "eigen6"}) {
    const std::string file = std::string(method) + ".exr";
    const Image a = LoadRepresentation(dir / "limited" / file).representation.maps();
    const Image b = LoadRepresentation(dir / "free" / file).representation.maps();
    ASSERT_TRUE(a.SameShape(b));
    const double difference = LargestDifference(a, b);
    std::printf("%s: limited bands vs one band: largest difference %.3g\n", method, difference);
    EXPECT_LE(difference, kBandDifferenceBound) << method;
  }
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

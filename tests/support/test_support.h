#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/image_io.h"

namespace photomat::testing {

// The real datasets (the shared/data folder) come from $PHOTOMAT_TEST_DATA, which .ci/run sets.
// Unset: nullopt, and the test skips with that reason. Set to a folder that does not exist: the
// test fails, because a misconfigured run must not look like a skipped one.
constexpr const char* kTestDataVariable = "PHOTOMAT_TEST_DATA";
std::optional<std::filesystem::path> TestDataDir();

// Resolves `relative` under the data folder, or skips/fails the current test as described above.
#define PHOTOMAT_TEST_DATA_OR_SKIP(var, relative)                                   \
  const auto var##_root = ::photomat::testing::TestDataDir();                       \
  if (!var##_root) {                                                                \
    GTEST_SKIP() << ::photomat::testing::kTestDataVariable                          \
                 << " is not set: this test needs the real datasets (shared/data)"; \
  }                                                                                 \
  const std::filesystem::path var = *var##_root / (relative);                       \
  ASSERT_TRUE(std::filesystem::exists(var))                                         \
      << var << " is missing but " << ::photomat::testing::kTestDataVariable << " is set"

// Whether two images have the same shape and the same float bits in every value (so -0 differs
// from 0 and a NaN equals the same NaN): for results that must be bit-identical.
bool SameBits(const Image& a, const Image& b);

// Largest |a - b| over the largest |b|, sample by sample (a failure if the shapes differ): how
// far two fits of the same maps differ, relative to the maps' scale.
double LargestDifferenceOverLargestValue(const Image& a, const Image& b);

// The names in `folder`, hidden ones (temporaries, scratch folders) included, sorted: what a
// command left there.
std::vector<std::string> EntriesOf(const std::filesystem::path& folder);

// How many times the regular expression `pattern` matches in `text` (non-overlapping): for
// counting elements of generated HTML or SVG.
std::size_t CountMatches(const std::string& text, const std::string& pattern);

// A fresh folder under the system temp folder, removed with its contents on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// Writes `contents` to `path` (creating parent folders); for building malformed inputs.
void WriteFile(const std::filesystem::path& path, const std::string& contents);

// Limits the size of files this process may write to `bytes` and makes larger writes fail with
// EFBIG instead of killing the process: a full disk, for tests of write errors (use in a child
// process, e.g. inside EXPECT_EXIT).
void LimitFileSize(std::size_t bytes);

// Integer images of 16 bits, linear (the write options of most test captures).
ImageWriteOptions Linear16Bit();

// The built photomat executable (for command-line tests).
std::filesystem::path PhotomatExecutable();

struct RunResult {
  int exit_code;       // -1 when the process did not exit normally (e.g. killed by a signal)
  std::string output;  // stdout and stderr, interleaved as written
};
// Runs the built photomat with `arguments` (passed through the shell, so quote paths with
// spaces) and collects what it prints.
RunResult RunPhotomat(const std::string& arguments);

struct RunLimits {
  // > 0: a hard limit on the child's address space (setrlimit RLIMIT_AS, soft and hard alike,
  // set in the child before photomat starts): allocations beyond it fail.
  std::size_t address_space_bytes = 0;
  // > 0: a limit on the child's CPU time (RLIMIT_CPU, soft and hard alike): past it the kernel
  // stops the child (SIGXCPU, then SIGKILL), which RunResult reports as exit code -1.
  int cpu_seconds = 0;
};
RunResult RunPhotomat(const std::string& arguments, const RunLimits& limits);

// The address space `photomat COMMAND --help` needs (the program before it reads anything: its
// libraries, their static buffers, the threads they start when loaded), found by bisection on
// RLIMIT_AS to 4 MiB. Tests under an address-space limit set it this much plus the room their
// work needs, so that the room, not the machine's libraries, is what they test: 453 MiB for every
// command with the BLAS scripts/debian-packages.txt brings (ATLAS), about 0.3 GiB more where
// OpenBLAS is the system's BLAS (README "Streamed fitting"). Each probe may use 10 s of CPU:
// under too low a limit OpenBLAS retries its failed buffer allocation forever. A failed bisection
// (no limit up to 8 GiB lets it start) is a test failure.
std::size_t StartupAddressSpace(const std::string& command);

// `photomat generate --out FOLDER OPTIONS` (a synthetic capture), expected to succeed (a failure
// is a test failure with photomat's output). Returns FOLDER as a string for command lines.
std::string GenerateCapture(const std::filesystem::path& folder, const std::string& options);

}  // namespace photomat::testing

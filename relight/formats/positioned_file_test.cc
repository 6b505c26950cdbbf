#include "relight/formats/positioned_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// Runs written in any order land at their offsets after the header; the file appears only on
// Commit().
TEST(PositionedFileWriterTest, WritesRunsAtTheirOffsetsAndAppearsOnCommit) {
  testing::TempDir dir;
  const fs::path path = dir / "f.bin";
  PositionedFileWriter file(path, "HEAD\n", 11);
  const std::vector<std::uint8_t> last = {'4', '5', '6'}, first = {'1', '2', '3'};
  file.Write(8, last);
  file.Write(5, first);
  EXPECT_FALSE(fs::exists(path));
  file.Commit();
  EXPECT_EQ(ReadTextFile(path), "HEAD\n123456");
}

TEST(PositionedFileWriterTest, RunsPastTheEndAreRefusedAndNothingIsLeft) {
  testing::TempDir dir;
  {
    PositionedFileWriter file(dir / "f.bin", "H", 4);
    const std::vector<std::uint8_t> bytes = {1, 2};
    EXPECT_THAT([&] { file.Write(3, bytes); },
                ThrowsMessage<Error>(HasSubstr("past the file's end")));
  }
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
}  // namespace photomat

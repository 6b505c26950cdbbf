#include "core/atomic_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using testing::TempDir;

TEST(AtomicFileTest, WritesWholeFile) {
  TempDir dir;
  WriteTextFileAtomically(dir / "a.txt", "hello");
  EXPECT_EQ(ReadTextFile(dir / "a.txt"), "hello");
  WriteTextFileAtomically(dir / "a.txt", "bye");
  EXPECT_EQ(ReadTextFile(dir / "a.txt"), "bye");
}

TEST(AtomicFileTest, FailingWriterLeavesOldContentAndNoTemporary) {
  TempDir dir;
  WriteTextFileAtomically(dir / "a.txt", "old");
  EXPECT_THROW(WriteFileAtomically(dir / "a.txt",
                                   [](const std::filesystem::path& temp) {
                                     testing::WriteFile(temp, "half");
                                     throw std::runtime_error("disk full");
                                   }),
               Error);
  EXPECT_EQ(ReadTextFile(dir / "a.txt"), "old");
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++files;
  }
  EXPECT_EQ(files, 1);
}

// A pending file written in parts, its write-back started after each (and before the temporary
// exists, which must be harmless), commits whole; destroyed uncommitted, it leaves nothing.
TEST(AtomicFileTest, PendingFileWritesBackInPartsAndCommitsWhole) {
  TempDir dir;
  {
    PendingFile file(dir / "stack.bin");
    file.StartWriteback();
    std::string written;
    for (int part = 0; part < 4; ++part) {
      written += std::string(1 << 16, static_cast<char>('a' + part));
      testing::WriteFile(file.temp(), written);
      file.StartWriteback();
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "stack.bin"));
    file.Commit();
    EXPECT_EQ(ReadTextFile(dir / "stack.bin"), written);
  }
  {
    PendingFile abandoned(dir / "other.bin");
    testing::WriteFile(abandoned.temp(), "half");
    abandoned.StartWriteback();
  }
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++files;
  }
  EXPECT_EQ(files, 1);
}

TEST(AtomicFileTest, MissingFolderIsNamed) {
  try {
    WriteTextFileAtomically("/nonexistent-folder/a.txt", "x");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "/nonexistent-folder/a.txt");
  }
}

// A full disk, emulated by a file-size limit (RLIMIT_FSIZE) in a child process: writes beyond it
// fail with EFBIG as they would with ENOSPC.
TEST(AtomicFileDeathTest, WriteBeyondTheDiskLimitIsAnErrorAndLeavesNoFile) {
  TempDir dir;
  EXPECT_EXIT(
      {
        testing::LimitFileSize(4096);
        try {
          WriteTextFileAtomically(dir / "big.txt", std::string(100000, 'x'));
        } catch (const Error& e) {
          _exit(std::filesystem::is_empty(dir.path()) ? 0 : 2);
        }
        _exit(1);
      },
      ::testing::ExitedWithCode(0), "");
}

TEST(AtomicFileTest, ReadingMissingFileNamesIt) {
  EXPECT_THROW(ReadTextFile("/nonexistent/file"), Error);
}

}  // namespace
}  // namespace photomat

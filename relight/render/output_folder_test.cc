#include "relight/render/output_folder.h"

#include <gtest/gtest.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

void WriteMarked(const fs::path& folder, const std::string& body) {
  WriteTextFileAtomically(folder / "marker.json", R"({"format": "kind"})");
  WriteTextFileAtomically(folder / "body.txt", body);
}

std::size_t Entries(const fs::path& folder) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(folder), {}));
}

TEST(OutputFolderTest, WritesANewFolderAndReplacesItsOwnKind) {
  TempDir dir;
  WriteFolderAtomically(dir / "out", "marker.json", "kind",
                        [](const fs::path& temp) { WriteMarked(temp, "one"); });
  EXPECT_EQ(ReadTextFile(dir / "out" / "body.txt"), "one");
  WriteFolderAtomically(dir / "out", "marker.json", "kind", [](const fs::path& temp) {
    WriteTextFileAtomically(temp / "marker.json", R"({"format": "kind"})");
  });
  EXPECT_FALSE(fs::exists(dir / "out" / "body.txt"));  // replaced whole, not merged
  EXPECT_EQ(Entries(dir.path()), 1u);                  // no temporary or old folder left
}

TEST(OutputFolderTest, AFailedWriteLeavesThePreviousFolderAndNoTemporary) {
  TempDir dir;
  WriteFolderAtomically(dir / "out", "marker.json", "kind",
                        [](const fs::path& temp) { WriteMarked(temp, "one"); });
  EXPECT_THROW(WriteFolderAtomically(dir / "out", "marker.json", "kind",
                                     [](const fs::path& temp) {
                                       WriteMarked(temp, "two");
                                       throw Error("disk full");
                                     }),
               Error);
  EXPECT_EQ(ReadTextFile(dir / "out" / "body.txt"), "one");
  EXPECT_EQ(Entries(dir.path()), 1u);
  EXPECT_THROW(WriteFolderAtomically(dir / "new", "marker.json", "kind",
                                     [](const fs::path&) { throw std::runtime_error("boom"); }),
               Error);
  EXPECT_FALSE(fs::exists(dir / "new"));
  EXPECT_EQ(Entries(dir.path()), 1u);
}

TEST(OutputFolderTest, RefusesFoldersOfAnotherKindAndFiles) {
  TempDir dir;
  testing::WriteFile(dir / "other" / "marker.json", R"({"format": "something else"})");
  testing::WriteFile(dir / "plain" / "data.csv", "1,2");
  testing::WriteFile(dir / "file", "x");
  const auto write = [](const fs::path& temp) { WriteMarked(temp, "new"); };
  for (const char* name : {"other", "plain", "file"}) {
    try {
      WriteFolderAtomically(dir / name, "marker.json", "kind", write);
      FAIL() << name << " was replaced";
    } catch (const Error& error) {
      EXPECT_EQ(error.file(), dir / name);
    }
  }
  EXPECT_EQ(ReadTextFile(dir / "plain" / "data.csv"), "1,2");
  // An empty folder is fine.
  fs::create_directory(dir / "empty");
  WriteFolderAtomically(dir / "empty", "marker.json", "kind", write);
  EXPECT_EQ(ReadTextFile(dir / "empty" / "body.txt"), "new");
}

}  // namespace
}  // namespace photomat

#include "core/scratch_folder.h"

#include <gtest/gtest.h>

#include <fstream>
#include <stdexcept>

#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

fs::path FreshFolder(const std::string& name) {
  const fs::path folder = fs::path(::testing::TempDir()) / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

TEST(ScratchFolderTest, IsHiddenInItsParentAndRemovedWithItsFiles) {
  const fs::path parent = FreshFolder("scratch_removed");
  fs::path scratch;
  {
    const ScratchFolder folder(parent, "export");
    scratch = folder.path();
    EXPECT_EQ(scratch.parent_path(), parent);
    EXPECT_TRUE(scratch.filename().string().starts_with(".export.scratch-"));
    ASSERT_TRUE(fs::is_directory(scratch));
    fs::create_directories(scratch / "sub");
    std::ofstream(scratch / "sub" / "stack.exr") << "bytes";
  }
  EXPECT_FALSE(fs::exists(scratch));
  EXPECT_TRUE(fs::is_empty(parent));
}

TEST(ScratchFolderTest, IsRemovedWhenTheWorkThrows) {
  const fs::path parent = FreshFolder("scratch_thrown");
  EXPECT_THROW(
      {
        const ScratchFolder folder(parent, "export");
        std::ofstream(folder.path() / "partial.exr") << "half";
        throw std::runtime_error("the work failed mid-way");
      },
      std::runtime_error);
  EXPECT_TRUE(fs::is_empty(parent));
}

TEST(ScratchFolderTest, TwoAreDistinctAndAMovedOneIsRemovedOnce) {
  const fs::path parent = FreshFolder("scratch_two");
  ScratchFolder first(parent, "a");
  const ScratchFolder second(parent, "a");
  EXPECT_NE(first.path(), second.path());
  const fs::path path = first.path();
  {
    const ScratchFolder moved(std::move(first));
    EXPECT_EQ(moved.path(), path);
    EXPECT_TRUE(first.path().empty());  // NOLINT(bugprone-use-after-move): what a move leaves
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(fs::is_directory(second.path()));
}

TEST(ScratchFolderTest, AMissingParentIsAnErrorNamingIt) {
  const fs::path missing = fs::path(::testing::TempDir()) / "scratch_no_such_folder";
  fs::remove_all(missing);
  try {
    const ScratchFolder folder(missing, "export");
    FAIL() << "expected an Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("scratch_no_such_folder"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace photomat

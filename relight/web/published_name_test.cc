#include "relight/web/published_name.h"

#include <gtest/gtest.h>

namespace photomat {
namespace {

TEST(PublishedNameTest, KeepsOnlyTheLastComponent) {
  EXPECT_EQ(PublishedName("/home/me/captures/cat/"), "cat");
  EXPECT_EQ(PublishedName("/work/shared/data/diligent/cat"), "cat");
  EXPECT_EQ(PublishedName("/home/me/captures/cat/manifest.json"), "cat");
  EXPECT_EQ(PublishedName("stacks/ptm.exr"), "ptm.exr");
  EXPECT_EQ(PublishedName("../data/./ball//"), "ball");
  EXPECT_EQ(PublishedName("sample.ptm"), "sample.ptm");
  EXPECT_EQ(PublishedName(""), "");
  EXPECT_EQ(PublishedName("/"), "/");
}

}  // namespace
}  // namespace photomat

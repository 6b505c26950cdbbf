#include "core/markup.h"

#include <gtest/gtest.h>

namespace photomat {
namespace {

TEST(EscapeMarkupTest, EscapesEveryCharacterWithMeaningInTextOrAttributes) {
  EXPECT_EQ(EscapeMarkup(R"(<a href="x">Tom & Jerry's</a>)"),
            "&lt;a href=&quot;x&quot;&gt;Tom &amp; Jerry&#39;s&lt;/a&gt;");
}

TEST(EscapeMarkupTest, LeavesOtherTextAloneIncludingUtf8) {
  EXPECT_EQ(EscapeMarkup("img 01 (slant 45°).png"), "img 01 (slant 45°).png");
  EXPECT_EQ(EscapeMarkup(""), "");
}

TEST(EscapeMarkupTest, EscapedTextDoesNotDoubleDecode) {
  // An already escaped entity is text to escape again, not markup to keep.
  EXPECT_EQ(EscapeMarkup("&amp;"), "&amp;amp;");
}

}  // namespace
}  // namespace photomat

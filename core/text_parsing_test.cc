#include "core/text_parsing.h"

#include <gtest/gtest.h>

namespace photomat {
namespace {

TEST(TextParsingTest, SplitLinesDropsBomAndCarriageReturns) {
  const auto lines = SplitLines(
      "\xEF\xBB\xBF"
      "a b\r\nc\r\n\nd");
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0], "a b");
  EXPECT_EQ(lines[1], "c");
  EXPECT_EQ(lines[2], "");
  EXPECT_EQ(lines[3], "d");
}

TEST(TextParsingTest, ParseNumberAcceptsDecimalCommaOnly) {
  EXPECT_EQ(ParseNumber("0.25"), 0.25);
  EXPECT_EQ(ParseNumber("-1e-3"), -1e-3);
  EXPECT_EQ(ParseNumber("+2"), 2.0);
  EXPECT_EQ(ParseNumber("0,5"), 0.5);
  EXPECT_FALSE(ParseNumber("1,000.5"));
  EXPECT_FALSE(ParseNumber("0,5,1"));
  EXPECT_FALSE(ParseNumber("abc"));
  EXPECT_FALSE(ParseNumber("1.5x"));
  EXPECT_FALSE(ParseNumber("nan"));
  EXPECT_FALSE(ParseNumber("inf"));
  EXPECT_FALSE(ParseNumber(""));
}

TEST(TextParsingTest, SplitWhitespaceHandlesTabsAndRuns) {
  const auto tokens = SplitWhitespace("  a\t b   c ");
  ASSERT_EQ(tokens.size(), 3u);
  EXPECT_EQ(tokens[2], "c");
}

}  // namespace
}  // namespace photomat

#include "core/digest.h"

#include <gtest/gtest.h>

#include <string>

namespace photomat {
namespace {

// XXH64 reference values (xxHash's own sanity test vectors): the empty input with seed 0 and
// "abc" with seed 0.
TEST(DigestTest, MatchesXxh64ReferenceValues) {
  EXPECT_EQ(Digest64(std::string_view("")), 0xEF46DB3751D8E999ull);
  EXPECT_EQ(Digest64(std::string_view("abc")), 0x44BC2CF5AD770999ull);
}

TEST(DigestTest, ChainingDependsOnOrderAndSeed) {
  const std::uint64_t ab = Digest64("b", Digest64("a"));
  const std::uint64_t ba = Digest64("a", Digest64("b"));
  EXPECT_NE(ab, ba);
  EXPECT_NE(Digest64("abc", 1), Digest64("abc", 2));
  EXPECT_EQ(Digest64("abc", 7), Digest64("abc", 7));
}

}  // namespace
}  // namespace photomat

#include "core/enum_names.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace photomat {
namespace {

enum class Colour { kRed, kGreen, kBlue };
constexpr std::array<NamedValue<Colour>, 3> kColours = {
    {{Colour::kRed, "red"}, {Colour::kGreen, "green"}, {Colour::kBlue, "blue"}}};

TEST(EnumNamesTest, NamesReadBothWays) {
  for (const auto& [value, name] : kColours) {
    EXPECT_EQ(NameOf(value, kColours), name);
    EXPECT_EQ(ValueNamed(name, kColours, "colour"), value);
  }
  static_assert(NameOf(Colour::kBlue, kColours) == "blue");
  EXPECT_EQ(FindValueNamed("green", kColours), Colour::kGreen);
  EXPECT_EQ(FindValueNamed("Green", kColours), std::nullopt);
}

TEST(EnumNamesTest, AnUnknownNameListsTheChoices) {
  try {
    ValueNamed("mauve", kColours, "colour");
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_STREQ(error.what(), "unknown colour 'mauve' (red, green or blue)");
  }
}

}  // namespace
}  // namespace photomat

#include "apps/cli_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "core/error.h"

namespace photomat::app {
namespace {

// Parses `arguments` (after the command's name) into SetInputOptions as a command would.
SetInputOptions Parse(std::vector<std::string> arguments) {
  CLI::App command("test");
  SetInputOptions options;
  AddSetInputOptions(command, options);
  std::reverse(arguments.begin(), arguments.end());  // CLI11 takes them last first
  command.parse(arguments);
  return options;
}

TEST(SetInputOptionsTest, DefaultsApplyIntensitiesAndLeaveTheColourSpaceToTheInput) {
  const SetInputOptions options = Parse({"capture.lp"});
  EXPECT_EQ(options.input, "capture.lp");
  const LoadOptions load = options.ToLoadOptions();
  EXPECT_TRUE(load.apply_intensities);
  EXPECT_FALSE(load.untagged_colour_space.has_value());
}

TEST(SetInputOptionsTest, FlagsBecomeLoadOptions) {
  const LoadOptions load =
      Parse({"set", "--ignore-intensities", "--colour-space", "srgb"}).ToLoadOptions();
  EXPECT_FALSE(load.apply_intensities);
  ASSERT_TRUE(load.untagged_colour_space.has_value());
  EXPECT_EQ(*load.untagged_colour_space, ColourSpace::kSrgb);
}

TEST(SetInputOptionsTest, AnUnknownColourSpaceIsAnErrorNamingTheOption) {
  const SetInputOptions options = Parse({"set", "--colour-space", "rec709"});
  try {
    options.ToLoadOptions();
    FAIL() << "rec709 was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("--colour-space"), std::string::npos) << error.what();
  }
}

TEST(SetInputOptionsTest, TheInputIsRequired) {
  EXPECT_THROW(Parse({"--ignore-intensities"}), CLI::RequiredError);
}

TEST(FittedStackCompressionTest, AutoIsRleForAMaskedSetAndNoneForFullFrames) {
  EXPECT_EQ(FittedStackCompression(kAutoExrCompression, true), ExrCompression::kRle);
  EXPECT_EQ(FittedStackCompression(kAutoExrCompression, false), ExrCompression::kNone);
  // A name is what it says, mask or not.
  EXPECT_EQ(FittedStackCompression("zip", false), ExrCompression::kZip);
  EXPECT_EQ(FittedStackCompression("rle", false), ExrCompression::kRle);
  EXPECT_EQ(FittedStackCompression("none", true), ExrCompression::kNone);
  EXPECT_THROW(FittedStackCompression("dwaa", true), Error);
}

}  // namespace
}  // namespace photomat::app

#include "apps/light_profile_cli.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

namespace photomat::app {
namespace {

// Parses `arguments` as a command with the light-profile options and applies them to rbf.
Method ParsedRbf(std::vector<std::string> arguments) {
  CLI::App app;
  LightProfileCli options;
  AddLightProfileOptions(app, options);
  std::reverse(arguments.begin(), arguments.end());  // CLI11 takes them last first
  app.parse(arguments);
  std::vector<Method> methods = {Method::Parse("rbf")};
  ApplyLightProfileOptions(options, methods);
  return methods[0];
}

TEST(LightProfileCliTest, TheDefaultsAreTheLibrarys) {
  const Method rbf = ParsedRbf({});
  EXPECT_EQ(rbf.profile, Method::Parse("rbf").profile);
  EXPECT_EQ(rbf.profile.rbf_tail, RbfTail::kAffine);
  EXPECT_EQ(rbf.profile.leave_out, LeaveOut::kOne);
}

TEST(LightProfileCliTest, TailAndLeaveOutReachTheMethod) {
  const Method rbf = ParsedRbf({"--rbf-tail", "quadratic", "--leave-out", "edge", "--planes", "4"});
  EXPECT_EQ(rbf.profile.rbf_tail, RbfTail::kQuadratic);
  EXPECT_EQ(rbf.profile.leave_out, LeaveOut::kEdge);
  EXPECT_EQ(rbf.profile.planes, 4);
  EXPECT_EQ(ParsedRbf({"--leave-out", "block"}).profile.leave_out, LeaveOut::kBlock);
  EXPECT_EQ(ParsedRbf({"--leave-out", "side"}).profile.leave_out, LeaveOut::kSide);
}

TEST(LightProfileCliTest, AnUnknownChoiceIsAnError) {
  EXPECT_THROW(ParsedRbf({"--leave-out", "two"}), CLI::ValidationError);
  EXPECT_THROW(ParsedRbf({"--rbf-tail", "cubic"}), CLI::ValidationError);
}

}  // namespace
}  // namespace photomat::app

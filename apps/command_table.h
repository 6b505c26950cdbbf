#pragma once

#include <span>
#include <string>
#include <string_view>

namespace photomat::app {

// The optional components a command, or a part of one, needs (README "Optional components").
enum class Component { kLiveCapture, kSolids, kSurfacePatterns, kCarving, kNeural };

// One subcommand of `photomat`: its name and description (as `photomat --help` lists them), the
// program that implements it (`photomat NAME ...` runs `libexec/photomat/PROGRAM NAME ...`, so a
// command loads only the libraries it needs), and the component it needs, if any.
struct CommandInfo {
  std::string_view name;
  std::string_view description;
  std::string_view program;
  const Component* component = nullptr;
};

// Every subcommand, in the order of `photomat --help`.
std::span<const CommandInfo> Commands();
// The subcommand called `name`, or nullptr.
const CommandInfo* FindCommand(std::string_view name);
// The command that `photomat ARGUMENTS...` runs (arguments[0] is the subcommand's name), or
// nullptr: FindCommand's, except that `fit --method neural` runs in photomat-neural (IMPLEMENTER
// CHOICE: the neural basis's training links libtorch, whose ~290 shared libraries take seconds to
// load, so only that program links it and every other command starts as before).
const CommandInfo* FindCommandFor(std::span<char* const> arguments);
// The description of a listed subcommand (throws std::out_of_range for an unlisted name).
std::string_view CommandDescription(std::string_view name);

// What this build left out of `component`, e.g. "solid textures (PHOTOMAT_WITH_SOLIDS=OFF:
// OpenVDB not found)"; empty when the component is built.
std::string_view ComponentAbsence(Component component);
// "this photomat was built without solid textures (PHOTOMAT_WITH_SOLIDS=OFF: OpenVDB not found)".
std::string BuiltWithout(Component component);
// `description` as the help lists it: with " (not in this build: ...)" when `component` is set
// and left out.
std::string DescribeInThisBuild(std::string_view description, const Component* component);

// The top-level description and version of `photomat` (its help and --version).
std::string_view ProgramDescription();
std::string_view ProgramVersion();

}  // namespace photomat::app

#pragma once

#include <CLI/CLI.hpp>
#include <initializer_list>
#include <memory>
#include <string_view>

#include "apps/command_table.h"

namespace photomat::app {

// Registers a subcommand's options and action on the app (e.g. AddFitCommand in fit_command.h).
using AddCommandFunction = void (*)(CLI::App& app);

// The main() of every photomat program: the app as `photomat` (its description, --version), the
// subcommands the program implements, parsing, and errors printed as one line
// ("photomat: error: ...", exit status 1).
int RunCommands(int argc, char** argv, std::initializer_list<AddCommandFunction> commands);

// Adds the subcommand `name` of the command table (its description from there) to `app`.
CLI::App* AddListedCommand(CLI::App& app, std::string_view name);

// Gives `command` its options (`add_options` registers them into one Options object) and its
// action: `run` with those options once they are parsed. The object is shared with the callback,
// which CLI11 keeps beyond this call.
template <typename Options, typename Run>
void BindCommand(CLI::App& command, void (*add_options)(CLI::App&, Options&), Run run) {
  auto options = std::make_shared<Options>();
  add_options(command, *options);
  command.callback([options, run] { run(*options); });
}

// Adds a subcommand that this build left out: listed in the help as `description` with what is
// missing, it fails with BuiltWithout(component) whatever its arguments.
void AddAbsentCommand(CLI::App& parent, std::string_view name, std::string_view description,
                      Component component);

}  // namespace photomat::app

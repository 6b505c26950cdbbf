#pragma once

#include <CLI/CLI.hpp>
#include <initializer_list>
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

// Adds a subcommand that this build left out: listed in the help as `description` with what is
// missing, it fails with BuiltWithout(component) whatever its arguments.
void AddAbsentCommand(CLI::App& parent, std::string_view name, std::string_view description,
                      Component component);

}  // namespace photomat::app

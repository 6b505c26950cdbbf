#pragma once

#include <CLI/CLI.hpp>
#include <string_view>

namespace photomat::app {

// `photomat solid carve`, added to the `solid` subcommand with `description`. Built only with
// carving (PHOTOMAT_WITH_SOLIDS and PHOTOMAT_WITH_SURFACE_PATTERNS); otherwise solid_command.cc
// lists `carve` as left out of the build.
void AddSolidCarveCommand(CLI::App& solid, std::string_view description);

}  // namespace photomat::app

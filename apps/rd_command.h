#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat rd`: registers the options and the action on `app` (README "Commands").
void AddRdCommand(CLI::App& app);

}  // namespace photomat::app

#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat export`: registers the options and the action on `app` (README "Commands").
void AddExportCommand(CLI::App& app);

}  // namespace photomat::app

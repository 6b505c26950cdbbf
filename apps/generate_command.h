#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat generate`: registers the options and the action on `app` (README "Commands").
void AddGenerateCommand(CLI::App& app);

}  // namespace photomat::app

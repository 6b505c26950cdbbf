#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat relight`: registers the options and the action on `app` (README "Commands").
void AddRelightCommand(CLI::App& app);

}  // namespace photomat::app

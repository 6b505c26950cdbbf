#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat evaluate`: registers the options and the action on `app` (README "Commands").
void AddEvaluateCommand(CLI::App& app);

}  // namespace photomat::app

#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat fit`: registers the options and the action on `app` (README "Commands").
void AddFitCommand(CLI::App& app);

}  // namespace photomat::app

#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat synthesize`: registers the options and the action on `app` (README "Commands").
void AddSynthesizeCommand(CLI::App& app);

}  // namespace photomat::app

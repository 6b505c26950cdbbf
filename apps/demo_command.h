#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat demo`: registers the options and the action on `app` (README "Commands").
void AddDemoCommand(CLI::App& app);

}  // namespace photomat::app

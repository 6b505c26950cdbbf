#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat capture` and `photomat devices`: registers the options and the action on `app` (README
// "Commands").
void AddCaptureCommand(CLI::App& app);
void AddDevicesCommand(CLI::App& app);

}  // namespace photomat::app

#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat calibrate` (lights, flatfield, intensities, response, apply): registers the options and
// the action on `app` (README "Commands").
void AddCalibrateCommand(CLI::App& app);

}  // namespace photomat::app

#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat batch plan|run|slurm|status|summary|run-task`: registers the options and the actions
// on `app` (README "Collections").
void AddBatchCommand(CLI::App& app);

}  // namespace photomat::app

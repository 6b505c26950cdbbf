#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat evaluate INPUT --methods neural --hold-out-every K` (the photomat-neural program, which
// `photomat` runs for that method: command_table.h, FindCommandFor): one training without the
// held-out images, which it then predicts.
void AddNeuralEvaluateCommand(CLI::App& app);

}  // namespace photomat::app

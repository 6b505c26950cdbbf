#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// `photomat fit --method neural` (the photomat-neural program, which `photomat` runs for that
// method: command_table.h, FindCommandFor): trains the neural basis and writes its map stack.
void AddNeuralFitCommand(CLI::App& app);

}  // namespace photomat::app

#pragma once

#include <CLI/CLI.hpp>

#include "represent/neural/neural_fit.h"

namespace photomat::app {

// The neural training's options, the same in `fit --method neural` and `evaluate --methods
// neural` (photomat-neural): --neural-k, --neural-epochs, --neural-patience,
// --neural-sample-pixels, --neural-threads and --seed, their defaults NeuralFitOptions'.
void AddNeuralTrainingOptions(CLI::App& command, NeuralFitOptions& options);

}  // namespace photomat::app

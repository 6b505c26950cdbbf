// photomat-neural: `photomat fit --method neural` and `evaluate --methods neural`, the neural
// basis's training (libtorch), run by
// `photomat` (photomat.cc, command_table.h FindCommandFor) so that no other command loads libtorch.
#include "apps/cli_main.h"
#include "apps/neural_evaluate_command.h"
#include "apps/neural_fit_command.h"

int main(int argc, char** argv) {
  using namespace photomat::app;
  return RunCommands(argc, argv, {AddNeuralFitCommand, AddNeuralEvaluateCommand});
}

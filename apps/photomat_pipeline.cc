// photomat-pipeline: the core commands (`photomat generate`, fit, relight, evaluate, demo, export,
// synthesize), run by `photomat` (photomat.cc).
#include "apps/cli_main.h"
#include "apps/demo_command.h"
#include "apps/evaluate_command.h"
#include "apps/export_command.h"
#include "apps/fit_command.h"
#include "apps/generate_command.h"
#include "apps/relight_command.h"
#include "apps/synthesize_command.h"

int main(int argc, char** argv) {
  using namespace photomat::app;
  return RunCommands(argc, argv,
                     {AddGenerateCommand, AddFitCommand, AddRelightCommand, AddEvaluateCommand,
                      AddDemoCommand, AddExportCommand, AddSynthesizeCommand});
}

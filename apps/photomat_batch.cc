// photomat-batch: `photomat batch` (recipes, task plans, local runs and Slurm job arrays), run by
// `photomat` (photomat.cc).
#include "apps/batch_command.h"
#include "apps/cli_main.h"

int main(int argc, char** argv) {
  return photomat::app::RunCommands(argc, argv, {photomat::app::AddBatchCommand});
}

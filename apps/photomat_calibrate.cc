// photomat-calibrate: `photomat calibrate` (Ceres for the mirror-sphere refinement), run by
// `photomat` (photomat.cc).
#include "apps/calibrate_command.h"
#include "apps/cli_main.h"

int main(int argc, char** argv) {
  return photomat::app::RunCommands(argc, argv, {photomat::app::AddCalibrateCommand});
}

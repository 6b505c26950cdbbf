// photomat-solid: `photomat solid` (OpenVDB, nanoflann, xxHash; assimp for carve), run by
// `photomat` (photomat.cc).
#include "apps/cli_main.h"
#include "apps/solid_command.h"

int main(int argc, char** argv) {
  return photomat::app::RunCommands(argc, argv, {photomat::app::AddSolidCommand});
}

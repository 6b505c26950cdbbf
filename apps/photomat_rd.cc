// photomat-rd: `photomat rd` (assimp, pugixml), run by `photomat` (photomat.cc).
#include "apps/cli_main.h"
#include "apps/rd_command.h"

int main(int argc, char** argv) {
  return photomat::app::RunCommands(argc, argv, {photomat::app::AddRdCommand});
}

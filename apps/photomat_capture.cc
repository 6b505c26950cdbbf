// photomat-capture: `photomat capture` and `photomat devices` (libcamera, V4L2, TurboJPEG), run by
// `photomat` (photomat.cc).
#include "apps/capture_command.h"
#include "apps/cli_main.h"

int main(int argc, char** argv) {
  using namespace photomat::app;
  return RunCommands(argc, argv, {AddCaptureCommand, AddDevicesCommand});
}

// photomat: relightable material maps from photographs under many lights.
//
// This program only dispatches: `photomat NAME ARGS...` runs the program that implements NAME
// (libexec/photomat/photomat-pipeline, -capture, -calibrate, -solid, -rd, -neural for `fit --method
// neural`; see command_table.h)
// with the same arguments, so that each command loads only the shared libraries it needs (fit
// does not load libcamera, OpenVDB, assimp or Ceres) and `photomat --help` loads none of them.
// The help, --version and the errors for a missing or unknown subcommand are the same CLI11 app
// the programs build, with every subcommand listed.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <system_error>

#include "apps/command_table.h"

namespace {

namespace fs = std::filesystem;
using photomat::app::CommandInfo;

// libexec/photomat/PROGRAM beside the bin/ folder of this executable.
fs::path ProgramPath(std::string_view program) {
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  const fs::path bin = error ? fs::path(".") : self.parent_path();
  return bin.parent_path() / "libexec" / "photomat" / program;
}

int Fail(const std::string& message) {
  std::fprintf(stderr, "photomat: error: %s\n", message.c_str());
  return 1;
}

// Replaces this process with the command's program; returns only when that fails.
int RunProgram(const CommandInfo& command, char** argv) {
  if (command.component && !photomat::app::ComponentAbsence(*command.component).empty()) {
    return Fail(photomat::app::BuiltWithout(*command.component));
  }
  const fs::path program = ProgramPath(command.program);
  if (command.program == "photomat-neural") {
    // IMPLEMENTER CHOICE: libtorch's OpenMP threads (libgomp) spin while they wait for work by
    // default; on a shared machine (DiLiGenT cat, 2 cores, load average 9) that quadrupled the
    // training's CPU time and wall time against passive waiting (4,000-pixel sample, 2 epochs:
    // 21.2 s wall, 8.5 s CPU spinning; 4.6 s, 1.8 s passive). libgomp reads the policy when it is
    // loaded, before main, so it is set here for the program's environment; a value the user set
    // is kept.
    setenv("OMP_WAIT_POLICY", "PASSIVE", 0);
  }
  execv(program.c_str(), argv);
  return Fail("cannot run " + program.string() + ": " + std::strerror(errno));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2) {
    if (const CommandInfo* command = photomat::app::FindCommandFor(
            std::span<char* const>(argv + 1, static_cast<std::size_t>(argc - 1)))) {
      return RunProgram(*command, argv);
    }
  }
  CLI::App app(std::string(photomat::app::ProgramDescription()), "photomat");
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(photomat::app::ProgramVersion()));
  for (const CommandInfo& command : photomat::app::Commands()) {
    app.add_subcommand(std::string(command.name),
                       photomat::app::DescribeInThisBuild(command.description, command.component));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  }
  // Only reachable with a subcommand CLI11 knows and FindCommand does not: none.
  return Fail("no program for this subcommand");
}

// photomat: relightable material maps from photographs under many lights.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <exception>

#include "apps/commands.h"
#include "core/error.h"

int main(int argc, char** argv) {
  spdlog::set_pattern("photomat: %l: %v");
  CLI::App app(
      "photomat: turns photographs of a material sample under many known lights into relightable "
      "material maps.",
      "photomat");
  app.require_subcommand(1);
  app.set_version_flag("--version", "photomat 0.1.0");
  photomat::app::AddGenerateCommand(app);
  photomat::app::AddFitCommand(app);
  photomat::app::AddRelightCommand(app);
  photomat::app::AddEvaluateCommand(app);
  photomat::app::AddDemoCommand(app);
  photomat::app::AddCaptureCommand(app);
  photomat::app::AddDevicesCommand(app);
  photomat::app::AddSolidCommand(app);
  photomat::app::AddRdCommand(app);
  photomat::app::AddCalibrateCommand(app);
  photomat::app::AddExportCommand(app);
  photomat::app::AddSynthesizeCommand(app);
  photomat::app::AddBatchCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  } catch (const photomat::Error& error) {
    fmt::print(stderr, "photomat: error: {}\n", error.what());
    return 1;
  } catch (const std::exception& error) {
    fmt::print(stderr, "photomat: error: {}\n", error.what());
    return 1;
  }
  return 0;
}

#pragma once

#include <CLI/CLI.hpp>

namespace photomat::app {

// Each subcommand registers its options and its action on the top-level app. The action runs
// after parsing; it throws photomat::Error on bad input, which main() prints as one line.
void AddGenerateCommand(CLI::App& app);
void AddFitCommand(CLI::App& app);
void AddRelightCommand(CLI::App& app);
void AddEvaluateCommand(CLI::App& app);
void AddDemoCommand(CLI::App& app);
void AddCaptureCommand(CLI::App& app);
void AddDevicesCommand(CLI::App& app);
void AddSolidCommand(CLI::App& app);
void AddRdCommand(CLI::App& app);
void AddCalibrateCommand(CLI::App& app);
void AddExportCommand(CLI::App& app);
void AddSynthesizeCommand(CLI::App& app);
void AddBatchCommand(CLI::App& app);

}  // namespace photomat::app

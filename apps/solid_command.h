#pragma once

#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <memory>

namespace photomat::app {

// `photomat solid` (exemplar, from-views, grow, carve): registers the options and the action on
// `app` (README "Commands").
void AddSolidCommand(CLI::App& app);

// Shared by the solid subcommands: TBB limited to `threads` while the result lives (none for 0;
// results do not depend on it), and the seconds since `since`.
std::unique_ptr<tbb::global_control> LimitThreads(int threads);
double Seconds(std::chrono::steady_clock::time_point since);

}  // namespace photomat::app

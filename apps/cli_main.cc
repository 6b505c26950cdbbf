#include "apps/cli_main.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <exception>
#include <new>
#include <string>

#include "core/error.h"
#include "core/memory_limits.h"

namespace photomat::app {

int RunCommands(int argc, char** argv, std::initializer_list<AddCommandFunction> commands) {
  // Before any thread starts: under `ulimit -v`, malloc's per-thread arenas would otherwise
  // reserve much of the limit (core/memory_limits.h).
  FitMallocToAddressSpaceLimit();
  KeepFreedMemoryForReuse();
  spdlog::set_pattern("photomat: %l: %v");
  CLI::App app(std::string(ProgramDescription()), "photomat");
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(ProgramVersion()));
  for (AddCommandFunction add : commands) add(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  } catch (const std::bad_alloc&) {
    // Reached under a memory or address-space limit (ulimit -v, a batch system's) as well as
    // on a full machine; streamed commands can be told to hold less.
    fmt::print(stderr,
               "photomat: error: out of memory (an allocation failed; a limit on memory or "
               "address space, or too little memory for this work). `photomat fit` holds less "
               "with a smaller --memory budget\n");
    return 1;
  } catch (const std::exception& error) {
    fmt::print(stderr, "photomat: error: {}\n", error.what());
    return 1;
  }
  return 0;
}

CLI::App* AddListedCommand(CLI::App& app, std::string_view name) {
  return app.add_subcommand(std::string(name), std::string(CommandDescription(name)));
}

void AddAbsentCommand(CLI::App& parent, std::string_view name, std::string_view description,
                      Component component) {
  CLI::App* command =
      parent.add_subcommand(std::string(name), DescribeInThisBuild(description, &component));
  command->allow_extras();
  command->set_help_flag();
  command->callback([component] { throw Error(BuiltWithout(component)); });
}

}  // namespace photomat::app

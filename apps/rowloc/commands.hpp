// Registration of the rowloc subcommands, one source file per subcommand.
#pragma once

#include <CLI/CLI.hpp>

namespace rowloc::apps {

/// Adds every subcommand to the application.
void RegisterCommands(CLI::App& app);

void RegisterExampleCommand(CLI::App& app);    // example_command.cpp
void RegisterMapCommands(CLI::App& app);       // map_commands.cpp
void RegisterMappingCommands(CLI::App& app);   // mapping_commands.cpp

}  // namespace rowloc::apps

// Registration of the rowloc subcommands, one source file per subcommand.
#pragma once

#include <CLI/CLI.hpp>

namespace rowloc::apps {

/// Adds every subcommand to the application.
void RegisterCommands(CLI::App& app);

void RegisterExampleCommand(CLI::App& app);    // example_command.cpp
void RegisterMapCommands(CLI::App& app);       // map_commands.cpp
void RegisterMappingCommands(CLI::App& app);   // mapping_commands.cpp
void RegisterWorldCommand(CLI::App& app);      // world_command.cpp
void RegisterSimulateCommand(CLI::App& app);   // simulate_command.cpp
void RegisterEvaluateCommand(CLI::App& app);   // evaluate_command.cpp
void RegisterReplayCommand(CLI::App& app);     // replay_command.cpp

}  // namespace rowloc::apps

// Registration of the rowloc subcommands, one source file per subcommand.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string_view>

namespace rowloc::apps {

/// Exit status of a subcommand whose input (files, options, data) is unusable.
inline constexpr int kInputErrorExitCode = 2;

/// Runs a subcommand's body; an exception is logged as "<command>: <what>" and ends the program
/// with kInputErrorExitCode (the simulate, evaluate and replay commands share this contract).
void RunReportingInputErrors(std::string_view command, const std::function<void()>& body);

/// Adds every subcommand to the application.
void RegisterCommands(CLI::App& app);

void RegisterExampleCommand(CLI::App& app);    // example_command.cpp
void RegisterMapCommands(CLI::App& app);       // map_commands.cpp
void RegisterMapBuildCommands(CLI::App& app);  // map_build_command.cpp (after RegisterMapCommands)
void RegisterMappingCommands(CLI::App& app);   // mapping_commands.cpp
void RegisterWorldCommand(CLI::App& app);      // world_command.cpp
void RegisterSimulateCommand(CLI::App& app);   // simulate_command.cpp
void RegisterEvaluateCommand(CLI::App& app);   // evaluate_command.cpp
void RegisterReplayCommand(CLI::App& app);     // replay_command.cpp
void RegisterServeCommand(CLI::App& app);      // serve_command.cpp
void RegisterSendCommand(CLI::App& app);       // send_command.cpp

}  // namespace rowloc::apps

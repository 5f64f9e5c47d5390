// Registration of the rowloc subcommands, one source file per subcommand.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::apps {

/// Exit statuses, one rule for every command: 0 success, 2 bad input (files, options, data, an
/// output that cannot or must not be written), 1 internal failure (out of memory, a bug).
inline constexpr int kInputErrorExitCode = 2;
inline constexpr int kInternalErrorExitCode = 1;

/// Runs a subcommand's body; an exception is logged on stderr as "<command>: <what>" and ends the
/// program with kInputErrorExitCode, or kInternalErrorExitCode for std::bad_alloc and a
/// std::logic_error that is not one of its input-error kinds (invalid_argument, domain_error,
/// length_error, out_of_range).
void RunReportingInputErrors(std::string_view command, const std::function<void()>& body);

/// A path given on the command line, with the option or argument name that gave it.
struct NamedPath {
  std::string label;
  std::string path;
};

/// Checks the files of a command before anything is read or written: every input exists and is
/// not a directory; no output names an input or another output (also through links), and no
/// output is an existing non-regular file (mapio::CheckOutputPaths). Empty paths are skipped.
/// Throws std::invalid_argument naming the option, the path and the reason.
void CheckCommandFiles(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);

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
void RegisterConfigCommand(CLI::App& app);     // config_command.cpp
void RegisterCalibrateCommand(CLI::App& app);  // calibrate_command.cpp

}  // namespace rowloc::apps

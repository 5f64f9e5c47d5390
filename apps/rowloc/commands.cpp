#include "commands.hpp"

#include <spdlog/spdlog.h>

#include <exception>

namespace rowloc::apps {

void RunReportingInputErrors(std::string_view command, const std::function<void()>& body) {
  try {
    body();
  } catch (const std::exception& e) {
    spdlog::error("{}: {}", command, e.what());
    throw CLI::RuntimeError(kInputErrorExitCode);
  }
}

void RegisterCommands(CLI::App& app) {
  RegisterExampleCommand(app);
  RegisterMapCommands(app);
  RegisterMapBuildCommands(app);
  RegisterMappingCommands(app);
  RegisterWorldCommand(app);
  RegisterSimulateCommand(app);
  RegisterEvaluateCommand(app);
  RegisterReplayCommand(app);
  RegisterServeCommand(app);
  RegisterSendCommand(app);
}

}  // namespace rowloc::apps

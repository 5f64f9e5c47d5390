#include "commands.hpp"

namespace rowloc::apps {

void RegisterCommands(CLI::App& app) {
  RegisterExampleCommand(app);
  RegisterMapCommands(app);
  RegisterMappingCommands(app);
  RegisterWorldCommand(app);
  RegisterSimulateCommand(app);
  RegisterEvaluateCommand(app);
  RegisterReplayCommand(app);
}

}  // namespace rowloc::apps

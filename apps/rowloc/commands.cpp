#include "commands.hpp"

namespace rowloc::apps {

void RegisterCommands(CLI::App& app) {
  RegisterExampleCommand(app);
  RegisterMapCommands(app);
  RegisterMappingCommands(app);
}

}  // namespace rowloc::apps

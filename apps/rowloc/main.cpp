// rowloc: command line of the rowloc localization toolkit. Subcommands are registered by
// functions declared in commands.hpp, one source file each.
#include "commands.hpp"

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <exception>

int main(int argc, char** argv) {
  CLI::App app{"rowloc: map-aided localization between crop rows"};
  app.require_subcommand(1);
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Log debug messages");
  rowloc::apps::RegisterCommands(app);
  app.parse_complete_callback([&verbose] {
    spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info);
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::Error& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}

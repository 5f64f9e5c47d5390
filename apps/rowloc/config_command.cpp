// `rowloc config show [--filter FILE]`: prints on stdout the effective configuration a file
// loads to, as a complete canonical JSON document: every key with its value, whether the file
// states it or leaves it to the code's defaults. Without an option: the filter defaults.
#include "commands.hpp"

#include "rowloc/localization/filter_config.hpp"

#include <spdlog/spdlog.h>

#include <iostream>
#include <memory>
#include <string>

namespace rowloc::apps {
namespace {

struct ConfigShowOptions {
  std::string filter_path;
};

void RunConfigShow(const ConfigShowOptions& o) {
  CheckCommandFiles({{"--filter", o.filter_path}}, {});
  localization::FilterConfig config;
  if (!o.filter_path.empty()) {
    config = localization::LoadFilterConfig(o.filter_path);
    spdlog::info("filter {}", o.filter_path);
  } else {
    spdlog::info("filter: the built-in defaults");
  }
  std::cout << localization::FilterConfigJson(config) << std::flush;
}

}  // namespace

void RegisterConfigCommand(CLI::App& app) {
  CLI::App* config = app.add_subcommand("config", "Configuration files: their effective values");
  config->require_subcommand(1);
  auto o = std::make_shared<ConfigShowOptions>();
  CLI::App* show = config->add_subcommand(
      "show", "Print the effective configuration as complete JSON (every key, defaults included)");
  show->add_option("--filter", o->filter_path, "Filter file (config/filters/*.json); default: the built-in defaults");
  show->callback([o] { RunReportingInputErrors("config show", [&o] { RunConfigShow(*o); }); });
}

}  // namespace rowloc::apps

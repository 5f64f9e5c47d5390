// `rowloc config show [--filter FILE] [--vehicle FILE] [--scenario FILE]`: prints on stdout the
// effective configuration a file loads to, as one complete canonical JSON document: every key with
// its value, whether the file states it, inherits it from a file it extends, or leaves it to the
// code's defaults (docs/localization-filter.md §3).
//   --filter F              what the filter file F loads to
//   --vehicle V             the filter `rowloc replay --vehicle V` uses: V's recommended_filter,
//                           else the built-in defaults (with --filter: F, as replay)
//   --scenario S            the scenario S with the files it extends merged (docs/simulation-scenarios.md)
//   (none)                  the built-in filter defaults
// The log (stderr) says which file was read.
#include "commands.hpp"

#include "rowloc/localization/filter_choice.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/mapio/vehicle_config.hpp"
#include "rowloc/sim/scenario.hpp"

#include <spdlog/spdlog.h>

#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

namespace rowloc::apps {
namespace {

struct ConfigShowOptions {
  std::string filter_path;
  std::string vehicle_path;
  std::string scenario_path;
};

void RunConfigShow(const ConfigShowOptions& o) {
  CheckCommandFiles({{"--filter", o.filter_path}, {"--vehicle", o.vehicle_path}, {"--scenario", o.scenario_path}},
                    {});
  if (!o.scenario_path.empty()) {
    if (!o.filter_path.empty() || !o.vehicle_path.empty()) {
      throw std::invalid_argument("--scenario shows a scenario: give it alone, without --filter or --vehicle");
    }
    std::cout << sim::ExpandedScenarioJson(o.scenario_path) << std::flush;
    spdlog::info("scenario {}", o.scenario_path);
    return;
  }
  localization::FilterChoice choice;
  if (!o.vehicle_path.empty()) {
    choice = localization::ChooseFilter(o.filter_path, mapio::LoadVehicleFile(o.vehicle_path), o.vehicle_path);
  } else if (!o.filter_path.empty()) {
    choice = {localization::LoadFilterConfig(o.filter_path), o.filter_path, localization::FilterSource::kGiven};
  }
  std::cout << localization::FilterConfigJson(choice.config) << std::flush;
  spdlog::info("{}", localization::DescribeFilterChoice(choice, o.vehicle_path));
}

}  // namespace

void RegisterConfigCommand(CLI::App& app) {
  CLI::App* config = app.add_subcommand("config", "Configuration files: the values they load to");
  config->require_subcommand(1);
  auto o = std::make_shared<ConfigShowOptions>();
  CLI::App* show = config->add_subcommand(
      "show", "Print the effective configuration as complete JSON (every key, defaults and extended files included)");
  show->add_option("--filter", o->filter_path, "Filter file (config/filters/*.json); default: the built-in defaults");
  show->add_option("--vehicle", o->vehicle_path,
                   "Vehicle file: show the filter `rowloc replay --vehicle` would use (its recommended_filter, "
                   "unless --filter is given)");
  show->add_option("--scenario", o->scenario_path, "Scenario file: show it with the files it extends merged");
  show->callback([o] { RunReportingInputErrors("config show", [&o] { RunConfigShow(*o); }); });
}

}  // namespace rowloc::apps

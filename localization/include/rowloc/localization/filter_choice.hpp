// Which filter configuration a run uses (issue 29): the filter file the user names, else the one
// the vehicle file recommends ("recommended_filter", mapio/vehicle_config.hpp), else the built-in
// defaults. `rowloc replay`, `rowloc send`, `rowloc config show` and the service's sessions
// choose by this rule (docs/localization-filter.md §3, docs/service.md §3).
#pragma once

#include "rowloc/localization/filter_config.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace rowloc::localization {

/// Where a run's filter configuration came from.
enum class FilterSource {
  kGiven,        ///< a filter file (or configuration) the user named
  kRecommended,  ///< the vehicle file's recommended_filter
  kDefaults      ///< the built-in defaults (FilterConfig{})
};
/// "given", "vehicle" or "defaults".
std::string_view FilterSourceName(FilterSource source);

struct FilterChoice {
  FilterConfig config;
  std::filesystem::path file;  ///< the filter file read; empty for the defaults
  FilterSource source = FilterSource::kDefaults;
};

/// The vehicle's recommended filter, read; nullopt when the vehicle file names none. Throws
/// FilterConfigError "<vehicle_file>: recommended_filter: <the filter file's error>" when it cannot
/// be read or is invalid.
std::optional<FilterChoice> LoadRecommendedFilter(const mapio::VehicleFile& vehicle,
                                                  const std::filesystem::path& vehicle_file);

/// `filter_file` when it is not empty, else the vehicle's recommended filter, else the defaults.
/// Throws FilterConfigError.
FilterChoice ChooseFilter(const std::filesystem::path& filter_file, const mapio::VehicleFile& vehicle,
                          const std::filesystem::path& vehicle_file);

/// For logs: "filter differential (config/filters/differential.json, recommended by
/// config/vehicles/differential.json)", "filter x (x.json)", "filter default (the built-in defaults)".
std::string DescribeFilterChoice(const FilterChoice& choice, const std::filesystem::path& vehicle_file);

}  // namespace rowloc::localization

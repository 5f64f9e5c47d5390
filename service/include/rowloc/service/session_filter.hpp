// The filter configuration of a session being opened (docs/service.md §3): the filter the request
// names (`filter`: a file of the filters directory, which may extend other files; `filter_config`:
// inline, an overlay on the built-in defaults), else the recommended_filter of the vehicle file the
// request names (`vehicle`), else the built-in defaults. An inline vehicle (`vehicle_config`) has
// no file to resolve its recommended_filter against: without a filter it gets the defaults.
//
// The configuration is kept complete (every key, localization::FilterConfigJson), the defaults'
// too: it goes into the session's journal (SESSION.session.json), so that a resumed session runs
// with the values it was opened with, whatever the files or the code's defaults are when it resumes.
#pragma once

#include "rowloc/localization/filter_choice.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace rowloc::service {

struct SessionFilter {
  nlohmann::json config;  ///< the complete configuration (every key, also for the defaults)
  std::string name;       ///< the filter file's name (the recommended one's too), "" inline or for the defaults
  localization::FilterSource source = localization::FilterSource::kDefaults;
};

/// `filter`: the request's filter as read (the named file's JSON, or the inline object), or null;
/// `filter_file`: the named file's path ("" when inline or absent) and `filter_name` its name.
/// `vehicle` and `vehicle_file`: the same for the vehicle. Throws ServiceError kInvalidConfig naming
/// the filter (or the vehicle whose recommended filter is refused) and the reason.
SessionFilter ResolveSessionFilter(const nlohmann::json& filter, const std::filesystem::path& filter_file,
                                   const std::string& filter_name, const nlohmann::json& vehicle,
                                   const std::filesystem::path& vehicle_file, const std::string& vehicle_name);

}  // namespace rowloc::service

// The filter of a session being opened (session_filter.hpp).
#include "rowloc/service/session_filter.hpp"

#include "rowloc/service/service_error.hpp"

namespace rowloc::service {
namespace {

nlohmann::json Complete(const localization::FilterConfig& config) {
  return nlohmann::json::parse(localization::FilterConfigJson(config));
}

/// The built-in defaults, as their values today: a session resumed under another build keeps them.
SessionFilter Defaults() { return {Complete(localization::FilterConfig{}), "", localization::FilterSource::kDefaults}; }

}  // namespace

SessionFilter ResolveSessionFilter(const nlohmann::json& filter, const std::filesystem::path& filter_file,
                                   const std::string& filter_name, const nlohmann::json& vehicle,
                                   const std::filesystem::path& vehicle_file, const std::string& vehicle_name) {
  try {
    if (!filter.is_null() && !filter_file.empty()) {  // by name: extends resolve in the filters directory
      return {Complete(localization::ParseFilterConfigFile(filter.dump(), filter_file)), filter_name,
              localization::FilterSource::kGiven};
    }
    if (!filter.is_null()) {
      return {Complete(localization::ParseFilterConfig(filter.dump(), "filter_config")), "",
              localization::FilterSource::kGiven};
    }
  } catch (const localization::FilterConfigError& e) {
    throw ServiceError(ErrorCode::kInvalidConfig, filter_name.empty() ? std::string(e.what())
                                                                      : "filter '" + filter_name + "': " + e.what());
  }
  if (vehicle_file.empty()) return Defaults();
  try {
    const mapio::VehicleFile file = mapio::ParseVehicleFile(vehicle.dump(), vehicle_file);
    if (auto recommended = localization::LoadRecommendedFilter(file, vehicle_file)) {
      return {Complete(recommended->config), recommended->file.stem().string(), localization::FilterSource::kRecommended};
    }
  } catch (const std::exception& e) {
    throw ServiceError(ErrorCode::kInvalidConfig, "vehicle '" + vehicle_name + "': " + e.what());
  }
  return Defaults();
}

}  // namespace rowloc::service

// The filter of a run (filter_choice.hpp).
#include "rowloc/localization/filter_choice.hpp"

namespace rowloc::localization {

std::string_view FilterSourceName(FilterSource source) {
  switch (source) {
    case FilterSource::kGiven: return "given";
    case FilterSource::kRecommended: return "vehicle";
    case FilterSource::kDefaults: return "defaults";
  }
  return "?";
}

std::optional<FilterChoice> LoadRecommendedFilter(const mapio::VehicleFile& vehicle,
                                                  const std::filesystem::path& vehicle_file) {
  if (!vehicle.recommended_filter) return std::nullopt;
  try {
    return FilterChoice{LoadFilterConfig(*vehicle.recommended_filter), *vehicle.recommended_filter,
                        FilterSource::kRecommended};
  } catch (const FilterConfigError& e) {
    throw FilterConfigError(vehicle_file.string() + ": recommended_filter: " + e.what());
  }
}

FilterChoice ChooseFilter(const std::filesystem::path& filter_file, const mapio::VehicleFile& vehicle,
                          const std::filesystem::path& vehicle_file) {
  if (!filter_file.empty()) return {LoadFilterConfig(filter_file), filter_file, FilterSource::kGiven};
  if (auto recommended = LoadRecommendedFilter(vehicle, vehicle_file)) return std::move(*recommended);
  return {};
}

std::string DescribeFilterChoice(const FilterChoice& choice, const std::filesystem::path& vehicle_file) {
  const std::string head = "filter " + choice.config.name + " (";
  switch (choice.source) {
    case FilterSource::kGiven: return head + choice.file.string() + ")";
    case FilterSource::kRecommended:
      return head + choice.file.string() + ", recommended by " + vehicle_file.string() + ")";
    case FilterSource::kDefaults: return head + "the built-in defaults)";
  }
  return head + ")";
}

}  // namespace rowloc::localization

// Which filter a run uses (issue 29, filter_choice.hpp): the file the user names, else the vehicle
// file's recommended_filter, else the built-in defaults; errors name the vehicle file that
// recommends a filter that cannot be read; every shipped vehicle's recommended filter loads.
#include "rowloc/localization/filter_choice.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>

namespace rowloc::localization {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::filesystem::path Shipped(const std::string& sub) { return test::SourceDir() / "config" / sub; }

/// The shipped differential vehicle, recommending `filter` (nullopt: none).
mapio::VehicleFile Differential(std::optional<std::filesystem::path> filter) {
  return {mapio::DifferentialDriveConfig(), std::move(filter)};
}

std::string Json(const FilterConfig& config) { return FilterConfigJson(config); }

TEST(ChooseFilter, AGivenFileComesFirst) {
  const std::filesystem::path given = Shipped("filters") / "wheel-angles.json";
  const FilterChoice choice =
      ChooseFilter(given, Differential(Shipped("filters") / "differential.json"), "differential.json");
  EXPECT_EQ(choice.source, FilterSource::kGiven);
  EXPECT_EQ(choice.file, given);
  EXPECT_EQ(Json(choice.config), Json(LoadFilterConfig(given)));
}

TEST(ChooseFilter, ThenTheVehiclesRecommendedFilter) {
  const std::filesystem::path recommended = Shipped("filters") / "differential.json";
  const FilterChoice choice = ChooseFilter("", Differential(recommended), "v.json");
  EXPECT_EQ(choice.source, FilterSource::kRecommended);
  EXPECT_EQ(choice.file, recommended);
  EXPECT_EQ(choice.config.name, "differential");
  EXPECT_EQ(choice.config.wheels.speed_sigma_radps, 0.06345);
  EXPECT_EQ(Json(choice.config), Json(LoadFilterConfig(recommended)));
}

TEST(ChooseFilter, ElseTheBuiltInDefaults) {
  const FilterChoice choice = ChooseFilter("", Differential(std::nullopt), "v.json");
  EXPECT_EQ(choice.source, FilterSource::kDefaults);
  EXPECT_TRUE(choice.file.empty());
  EXPECT_EQ(Json(choice.config), Json(FilterConfig{}));
  EXPECT_FALSE(LoadRecommendedFilter(Differential(std::nullopt), "v.json").has_value());
}

TEST(ChooseFilter, AGivenFileIsReadEvenWhenTheRecommendedOneIsBroken) {
  // The recommended filter is not opened when a filter is given.
  const FilterChoice choice = ChooseFilter(Shipped("filters") / "default.json",
                                           Differential(std::filesystem::path("/no/such/filter.json")), "v.json");
  EXPECT_EQ(choice.source, FilterSource::kGiven);
}

std::string ErrorOf(const mapio::VehicleFile& vehicle, const std::filesystem::path& vehicle_file) {
  try {
    ChooseFilter("", vehicle, vehicle_file);
  } catch (const FilterConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no FilterConfigError";
  return "";
}

TEST(ChooseFilter, AMissingRecommendedFilterNamesTheVehicleFileAndTheFilter) {
  EXPECT_EQ(ErrorOf(Differential(std::filesystem::path("cfg/../filters/absent.json")), "cfg/vehicle.json"),
            "cfg/vehicle.json: recommended_filter: cfg/../filters/absent.json: cannot open filter file: No such file "
            "or directory");
}

TEST(ChooseFilter, AnInvalidRecommendedFilterNamesTheVehicleFileTheFilterAndTheKey) {
  const std::filesystem::path bad = test::SourceDir() / "tests" / "data" / "filters" / "bad-gate.json";
  EXPECT_THAT(ErrorOf(Differential(bad), "cfg/vehicle.json"),
              AllOf(HasSubstr("cfg/vehicle.json: recommended_filter: "), HasSubstr("bad-gate.json"),
                    HasSubstr("gate_probability")));
}

TEST(ChooseFilter, AGivenFileThatIsMissingIsNotBlamedOnTheVehicle) {
  try {
    ChooseFilter("absent.json", Differential(Shipped("filters") / "differential.json"), "cfg/vehicle.json");
    ADD_FAILURE() << "no FilterConfigError";
  } catch (const FilterConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("absent.json"));
    EXPECT_THAT(e.what(), ::testing::Not(HasSubstr("recommended_filter")));
  }
}

TEST(DescribeFilterChoice, SaysWhereTheFilterCameFrom) {
  FilterConfig differential;
  differential.name = "differential";
  EXPECT_EQ(DescribeFilterChoice({differential, "config/filters/differential.json", FilterSource::kRecommended},
                                 "config/vehicles/differential.json"),
            "filter differential (config/filters/differential.json, recommended by config/vehicles/differential.json)");
  FilterConfig angles;
  angles.name = "wheel-angles";
  EXPECT_EQ(DescribeFilterChoice({angles, "config/filters/wheel-angles.json", FilterSource::kGiven}, "v.json"),
            "filter wheel-angles (config/filters/wheel-angles.json)");
  EXPECT_EQ(DescribeFilterChoice(ChooseFilter("", Differential(std::nullopt), "v.json"), "v.json"),
            "filter default (the built-in defaults)");
}

TEST(FilterSourceName, NamesEachSource) {
  EXPECT_EQ(FilterSourceName(FilterSource::kGiven), "given");
  EXPECT_EQ(FilterSourceName(FilterSource::kRecommended), "vehicle");
  EXPECT_EQ(FilterSourceName(FilterSource::kDefaults), "defaults");
}

TEST(ShippedVehicleFiles, EachRecommendedFilterLoads) {
  std::size_t vehicles = 0;
  for (const auto& entry : std::filesystem::directory_iterator(Shipped("vehicles"))) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    ++vehicles;
    const mapio::VehicleFile vehicle = mapio::LoadVehicleFile(entry.path());
    const std::optional<FilterChoice> recommended = LoadRecommendedFilter(vehicle, entry.path());
    ASSERT_TRUE(recommended.has_value());
    EXPECT_EQ(recommended->source, FilterSource::kRecommended);
    EXPECT_EQ(recommended->config.name, recommended->file.stem().string());
  }
  EXPECT_GE(vehicles, 5u);
  // The differential's noise was identified (docs/localization-filter.md §5.8): its own file.
  const auto differential = Shipped("vehicles") / "differential.json";
  EXPECT_EQ(ChooseFilter("", mapio::LoadVehicleFile(differential), differential).config.name, "differential");
  const auto vineyard = Shipped("vehicles") / "vineyard-ugv-4ws.json";
  EXPECT_EQ(Json(ChooseFilter("", mapio::LoadVehicleFile(vineyard), vineyard).config), Json(FilterConfig{}));
}

}  // namespace
}  // namespace rowloc::localization

// The shipped filter files (config/filters/*.json) load to the values recorded in
// tests/data/config-expanded/filters/ (issue 29: "every file still loads to the same values"). The
// fixtures were written by `rowloc config show --filter FILE` (FilterConfigJson) from each file
// while it still listed every key, before the files became overlays on the code's defaults; this
// test compares the complete serialization, so a change of any default, of any file or of the
// loader shows here as the key that moved.
#include "rowloc/localization/filter_config.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

namespace rowloc::localization {
namespace {

using nlohmann::json;

std::filesystem::path ShippedDir() { return test::SourceDir() / "config" / "filters"; }
std::filesystem::path FixtureDir() { return test::SourceDir() / "tests" / "data" / "config-expanded" / "filters"; }

std::string TextOf(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::set<std::string> JsonStems(const std::filesystem::path& dir) {
  std::set<std::string> stems;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() == ".json") stems.insert(entry.path().stem().string());
  }
  return stems;
}

TEST(ShippedFilterFiles, EveryFileHasItsFixtureAndEveryFixtureItsFile) {
  EXPECT_EQ(JsonStems(ShippedDir()), JsonStems(FixtureDir()));
  EXPECT_GE(JsonStems(ShippedDir()).size(), 11u);
}

TEST(ShippedFilterFiles, EveryFileLoadsToItsRecordedValues) {
  for (const std::string& name : JsonStems(ShippedDir())) {
    SCOPED_TRACE(name);
    const FilterConfig loaded = LoadFilterConfig(ShippedDir() / (name + ".json"));
    const std::string fixture = TextOf(FixtureDir() / (name + ".json"));
    const std::string shown = FilterConfigJson(loaded);
    EXPECT_EQ(json::parse(shown), json::parse(fixture));  // names the key on a difference
    EXPECT_EQ(shown, fixture);                            // and the same bytes
  }
}

TEST(ShippedFilterFiles, TheSerializationReadsBackToTheSameValues) {
  for (const std::string& name : JsonStems(ShippedDir())) {
    SCOPED_TRACE(name);
    const FilterConfig loaded = LoadFilterConfig(ShippedDir() / (name + ".json"));
    const std::string shown = FilterConfigJson(loaded);
    EXPECT_EQ(FilterConfigJson(ParseFilterConfig(shown, name)), shown);
  }
}

TEST(FilterConfigJson, ListsTheInCodeDefaultsAndIsCanonical) {
  const std::string shown = FilterConfigJson(FilterConfig{});
  const json document = json::parse(shown);
  EXPECT_EQ(document["name"], "default");
  EXPECT_EQ(document["wheels"]["speed_update_iterations"], 1);
  EXPECT_EQ(document["map_aided"]["method"], "range");
  EXPECT_EQ(document["process_noise"]["gyro_bias_radps_per_sqrt_hz"].get<double>(),
            FilterConfig{}.process_noise.gyro_bias_radps_per_sqrt_hz);
  EXPECT_EQ(shown.back(), '\n');
  EXPECT_EQ(nlohmann::ordered_json::parse(shown).dump(2) + "\n", shown);  // two-space indent, the file's order
}

TEST(FilterConfigJson, KeepsEveryBitOfANumber) {
  FilterConfig config;
  config.name = "bits";
  config.map_aided.cone_half_angle_rad = 0.1 + 0.2;  // 0.30000000000000004
  config.process_noise.gyro_bias_radps_per_sqrt_hz = 1.0 / 3.0;
  config.vio.position_m = {-0.125, 1e-300};
  config.map_aided.method = MapAidedMethod::kEllipsoidCutDeprior;
  const FilterConfig back = ParseFilterConfig(FilterConfigJson(config), "bits");
  EXPECT_EQ(back.map_aided.cone_half_angle_rad, config.map_aided.cone_half_angle_rad);
  EXPECT_EQ(back.process_noise.gyro_bias_radps_per_sqrt_hz, config.process_noise.gyro_bias_radps_per_sqrt_hz);
  EXPECT_EQ(back.vio.position_m, config.vio.position_m);
  EXPECT_EQ(back.map_aided.method, MapAidedMethod::kEllipsoidCutDeprior);
  EXPECT_EQ(FilterConfigJson(back), FilterConfigJson(config));
}

}  // namespace
}  // namespace rowloc::localization

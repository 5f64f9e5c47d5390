// MapBuildConfig: the shipped default file, overlays on the defaults, strict reading, domains, round trip.
#include "rowloc/mapping/map_build_config.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

namespace rowloc::mapping {
namespace {

using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;

std::string Load(const std::filesystem::path& path) {
  try {
    LoadMapBuildConfig(path);
  } catch (const MapBuildConfigError& e) {
    return e.what();
  }
  return "";
}

class MapBuildConfigFileTest : public ::testing::Test {
 protected:
  std::filesystem::path Write(const std::string& text) {
    const auto path = dir_ / "config.json";
    std::ofstream(path) << text;
    return path;
  }
  std::string Default() const { return FormatMapBuildConfig(MapBuildConfig{}); }
  test::ScratchDir dir_;
};

TEST(MapBuildConfigTest, ShippedDefaultFileEqualsTheBuiltInDefaults) {
  const MapBuildConfig shipped = LoadMapBuildConfig(test::SourceDir() / "config/mapping/default.json");
  EXPECT_EQ(FormatMapBuildConfig(shipped), FormatMapBuildConfig(MapBuildConfig{}));
}

TEST(MapBuildConfigTest, DefaultsAreValid) { EXPECT_FALSE(ValidateMapBuildConfig(MapBuildConfig{}).has_value()); }

TEST(MapBuildConfigTest, ValidateNamesTheKeyOutsideItsDomain) {
  MapBuildConfig config;
  config.rows.max_gap_m = -1.0;
  const auto problem = ValidateMapBuildConfig(config);
  ASSERT_TRUE(problem.has_value());
  EXPECT_THAT(*problem, HasSubstr("rows.max_gap_m"));
  config = MapBuildConfig{};
  config.outline.edge_quantile = 1.5;
  EXPECT_THAT(ValidateMapBuildConfig(config).value_or(""), HasSubstr("outline.edge_quantile"));
}

TEST(MapBuildConfigTest, TheTileOverlapMustCoverTheGroundFitsNeighbourhood) {
  MapBuildConfig config;
  config.tiles.overlap_m = 1.5;
  config.terrain.classification_radius_m = 2.0;
  const auto problem = ValidateMapBuildConfig(config);
  ASSERT_TRUE(problem.has_value());
  EXPECT_THAT(*problem, HasSubstr("tiles.overlap_m: must be at least terrain.classification_radius_m (2), got 1.5"));
  config.tiles.overlap_m = 2.0;
  EXPECT_FALSE(ValidateMapBuildConfig(config).has_value());
  config.tiles.threads = 65;
  EXPECT_THAT(ValidateMapBuildConfig(config).value_or(""), HasSubstr("tiles.threads: must be in [0, 64]"));
}

TEST(MapBuildConfigTest, MeshLevelsAreNoneOrAtLeastTwoBetweenTheirHeights) {
  MapBuildConfig config;
  EXPECT_EQ(MeshLevelHeights(config.mesh).size(), 4U);
  EXPECT_DOUBLE_EQ(MeshLevelHeights(config.mesh).front(), 0.6);
  EXPECT_DOUBLE_EQ(MeshLevelHeights(config.mesh).back(), 1.6);
  config.mesh.levels = 0;
  EXPECT_TRUE(MeshLevelHeights(config.mesh).empty());
  EXPECT_FALSE(ValidateMapBuildConfig(config).has_value());
  config.mesh.levels = 1;
  EXPECT_THAT(ValidateMapBuildConfig(config).value_or(""), HasSubstr("mesh.levels: must be 0 (no meshes) or at least 2"));
  config.mesh.levels = 3;
  config.mesh.highest_m = 0.6;  // = lowest_m
  EXPECT_THAT(ValidateMapBuildConfig(config).value_or(""), HasSubstr("mesh.highest_m: must be above mesh.lowest_m"));
  config.mesh.highest_m = 1.0;
  EXPECT_EQ(MeshLevelHeights(config.mesh), (std::vector<double>{0.6, 0.8, 1.0}));
}

TEST_F(MapBuildConfigFileTest, FormatThenLoadRoundTrips) {
  MapBuildConfig config;
  config.band.reference_height_m = 1.25;
  config.rows.min_part_points = 42;
  const MapBuildConfig back = LoadMapBuildConfig(Write(FormatMapBuildConfig(config)));
  EXPECT_EQ(back.band.reference_height_m, 1.25);
  EXPECT_EQ(back.rows.min_part_points, 42);
  EXPECT_EQ(FormatMapBuildConfig(back), FormatMapBuildConfig(config));
}

TEST_F(MapBuildConfigFileTest, AFileIsAnOverlayOnTheDefaults) {
  // Keys and sections left out keep the code's defaults (a file written for an older version, which
  // lacks newer keys, still loads); the keys given change only themselves.
  EXPECT_EQ(FormatMapBuildConfig(LoadMapBuildConfig(Write("{}"))), Default());
  const MapBuildConfig overlay =
      LoadMapBuildConfig(Write(R"({"band": {"reference_height_m": 1.3}, "outline": {"one_sided_max_width_m": 0}})"));
  MapBuildConfig expected;
  expected.band.reference_height_m = 1.3;
  expected.outline.one_sided_max_width_m = 0.0;
  EXPECT_EQ(FormatMapBuildConfig(overlay), FormatMapBuildConfig(expected));
  // A misspelt section or key is not silently ignored.
  EXPECT_THAT(Load(Write(R"({"outlines": {"min_width_m": 0.2}})")), HasSubstr("outlines"));
  EXPECT_THAT(Load(Write(R"({"outline": {"min_widht_m": 0.2}})")), HasSubstr("min_widht_m"));
  // The overlay is validated as a whole: a key that breaks a relation with a default is named.
  EXPECT_THAT(Load(Write(R"({"tiles": {"overlap_m": 1}})")),
              HasSubstr("tiles.overlap_m: must be at least terrain.classification_radius_m"));
}

TEST_F(MapBuildConfigFileTest, UnknownKeyIsAnErrorNamingFileAndKey) {
  std::string text = Default();
  text.replace(text.find("\"max_gap_m\""), 11, "\"max_gap\"");
  const auto path = Write(text);
  const std::string error = Load(path);
  EXPECT_THAT(error, HasSubstr(path.string()));
  EXPECT_THAT(error, HasSubstr("rows.max_gap"));
}

TEST_F(MapBuildConfigFileTest, OutOfRangeAndWrongTypeAreErrors) {
  std::string text = Default();
  const auto at = text.find("\"voxel_size_m\": 0.02");
  ASSERT_NE(at, std::string::npos);
  EXPECT_THAT(Load(Write(std::string(text).replace(at, 20, "\"voxel_size_m\": -1"))),
              HasSubstr("clean.voxel_size_m: must be in [0, 1], got -1"));
  EXPECT_THAT(Load(Write(std::string(text).replace(at, 20, "\"voxel_size_m\": \"x\""))),
              HasSubstr("clean.voxel_size_m: must be a number"));
  EXPECT_THAT(Load(Write("{\"clean\": 3}")), HasSubstr("clean"));
  EXPECT_THAT(Load(Write("{\"clean\": {\"voxel_size_m\": null}}")), HasSubstr("clean.voxel_size_m"));
  EXPECT_THAT(Load(Write("[1, 2]")), Not(IsEmpty()));
  EXPECT_THAT(Load(Write("{ not json")), HasSubstr("invalid JSON"));
  // Each key in its domain, but the two together not: the file and both keys are named.
  std::string thin_overlap = text;
  const auto overlap = thin_overlap.find("\"overlap_m\": 3");
  ASSERT_NE(overlap, std::string::npos);
  thin_overlap.replace(overlap, 14, "\"overlap_m\": 1");
  const std::string error = Load(Write(thin_overlap));
  EXPECT_THAT(error, HasSubstr("tiles.overlap_m: must be at least terrain.classification_radius_m"));
  EXPECT_THAT(Load(dir_ / "nonexistent.json"), HasSubstr("nonexistent.json: cannot open"));
}

}  // namespace
}  // namespace rowloc::mapping

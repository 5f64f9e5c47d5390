#include "rowloc/sim/terrain_map.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <string>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;

TerrainPatch Square(TerrainClass terrain, double x0, double y0, double size) {
  return {terrain, {{x0, y0}, {x0 + size, y0}, {x0 + size, y0 + size}, {x0, y0 + size}}};
}

std::string ConstructionError(std::vector<TerrainPatch> patches) {
  try {
    TerrainMap map(TerrainClass::kGrass, std::move(patches));
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(no error)";
}

std::string ParseError(const std::string& text) {
  try {
    ParseTerrainMap(text, "scenario.json", "terrain_map");
  } catch (const TerrainConfigError& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(TerrainMapTest, DefaultEverywhereWithoutPatches) {
  const TerrainMap tiles;
  EXPECT_EQ(tiles.ClassAt({0, 0}), TerrainClass::kTiles);
  const TerrainMap mud(TerrainClass::kMud);
  EXPECT_EQ(mud.ClassAt({1e6, -3}), TerrainClass::kMud);
}

TEST(TerrainMapTest, PointInsideOutsideAndOnTheBoundary) {
  // An L-shaped (non-convex) patch, listed counter-clockwise.
  const TerrainMap map(TerrainClass::kGrass,
                       {{TerrainClass::kMud, {{0, 0}, {4, 0}, {4, 1}, {1, 1}, {1, 4}, {0, 4}}}});
  EXPECT_EQ(map.ClassAt({0.5, 0.5}), TerrainClass::kMud);
  EXPECT_EQ(map.ClassAt({3.5, 0.5}), TerrainClass::kMud);
  EXPECT_EQ(map.ClassAt({0.5, 3.5}), TerrainClass::kMud);
  EXPECT_EQ(map.ClassAt({2.0, 2.0}), TerrainClass::kGrass);  // in the notch
  EXPECT_EQ(map.ClassAt({-0.1, 0.5}), TerrainClass::kGrass);
  EXPECT_EQ(map.ClassAt({0.0, 2.0}), TerrainClass::kMud);    // boundary belongs to the patch
  EXPECT_EQ(map.ClassAt({4.0, 1.0}), TerrainClass::kMud);    // vertex
}

TEST(TerrainMapTest, OrientationDoesNotMatter) {
  TerrainPatch ccw = Square(TerrainClass::kGravel, 0, 0, 2);
  TerrainPatch cw = ccw;
  std::reverse(cw.polygon_m.begin(), cw.polygon_m.end());
  const TerrainMap a(TerrainClass::kTiles, {ccw}), b(TerrainClass::kTiles, {cw});
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 3.0);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector2d p(u(rng), u(rng));
    const bool inside = p.x() >= 0 && p.x() <= 2 && p.y() >= 0 && p.y() <= 2;
    ASSERT_EQ(a.ClassAt(p), inside ? TerrainClass::kGravel : TerrainClass::kTiles) << p.transpose();
    ASSERT_EQ(b.ClassAt(p), a.ClassAt(p));
  }
}

TEST(TerrainMapTest, LastListedPatchWins) {
  const TerrainMap map(TerrainClass::kTiles, {Square(TerrainClass::kGrass, 0, 0, 10), Square(TerrainClass::kMud, 2, 2, 3),
                                              Square(TerrainClass::kGravel, 4, 4, 3)});
  EXPECT_EQ(map.ClassAt({1, 1}), TerrainClass::kGrass);
  EXPECT_EQ(map.ClassAt({3, 3}), TerrainClass::kMud);
  EXPECT_EQ(map.ClassAt({4.5, 4.5}), TerrainClass::kGravel);  // in mud and gravel: gravel is later
  EXPECT_EQ(map.ClassAt({6.5, 6.5}), TerrainClass::kGravel);
  EXPECT_EQ(map.ClassAt({11, 1}), TerrainClass::kTiles);
  const TerrainMap reversed(TerrainClass::kTiles, {Square(TerrainClass::kGravel, 4, 4, 3), Square(TerrainClass::kMud, 2, 2, 3)});
  EXPECT_EQ(reversed.ClassAt({4.5, 4.5}), TerrainClass::kMud);
}

TEST(TerrainMapTest, ClosingVertexIsDropped) {
  TerrainPatch patch = Square(TerrainClass::kMud, 0, 0, 1);
  patch.polygon_m.push_back(patch.polygon_m.front());
  const TerrainMap map(TerrainClass::kTiles, {patch});
  EXPECT_EQ(map.patches()[0].polygon_m.size(), 4u);
  EXPECT_EQ(map.ClassAt({0.5, 0.5}), TerrainClass::kMud);
}

TEST(TerrainMapTest, RejectsInvalidPolygons) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(ConstructionError({{TerrainClass::kMud, {{0, 0}, {1, 0}}}}), HasSubstr("patches[0].polygon: needs at least 3"));
  EXPECT_THAT(ConstructionError({Square(TerrainClass::kMud, 0, 0, 1), {TerrainClass::kMud, {{0, 0}, {1, nan}, {0, 1}}}}),
              HasSubstr("patches[1].polygon: vertex 1 is not finite"));
  // A bow tie crosses itself.
  EXPECT_THAT(ConstructionError({{TerrainClass::kMud, {{0, 0}, {1, 1}, {1, 0}, {0, 1}}}}),
              HasSubstr("patches[0].polygon: not a simple polygon"));
  // Collinear points have no area.
  EXPECT_THAT(ConstructionError({{TerrainClass::kMud, {{0, 0}, {1, 0}, {2, 0}}}}), HasSubstr("not a simple polygon"));
  EXPECT_THAT(ConstructionError({{static_cast<TerrainClass>(9), {{0, 0}, {1, 0}, {0, 1}}}}),
              HasSubstr("patches[0].terrain"));
  EXPECT_THROW(TerrainMap(static_cast<TerrainClass>(-1)), std::invalid_argument);
  EXPECT_THROW(TerrainMap().ClassAt({nan, 0}), std::invalid_argument);
  EXPECT_THROW(TerrainMap().ClassAt({0, std::numeric_limits<double>::infinity()}), std::invalid_argument);
}

TEST(ParseTerrainMapTest, PolygonsAndRectangles) {
  const TerrainMap map = ParseTerrainMap(R"({"default": "grass", "patches": [
      {"terrain": "mud", "polygon": [[0, 0], [4, 0], [0, 4]]},
      {"terrain": "gravel", "rectangle": {"min": [1, 1], "max": [10, 2]}}]})",
                                         "scenario.json");
  EXPECT_EQ(map.default_terrain(), TerrainClass::kGrass);
  ASSERT_EQ(map.patches().size(), 2u);
  EXPECT_EQ(map.ClassAt({0.5, 3.0}), TerrainClass::kMud);
  EXPECT_EQ(map.ClassAt({1.5, 1.5}), TerrainClass::kGravel);  // in both: rectangle listed last
  EXPECT_EQ(map.ClassAt({9.0, 1.5}), TerrainClass::kGravel);
  EXPECT_EQ(map.ClassAt({9.0, 2.5}), TerrainClass::kGrass);
  EXPECT_EQ(ParseTerrainMap(R"({"default": "tiles", "patches": []})", "s").ClassAt({0, 0}), TerrainClass::kTiles);
}

TEST(ParseTerrainMapTest, ErrorsNameSourceKeyAndReason) {
  EXPECT_EQ(ParseError(R"({"patches": []})"), "scenario.json: terrain_map.default: missing key");
  EXPECT_EQ(ParseError(R"({"default": "grass"})"), "scenario.json: terrain_map.patches: missing key");
  EXPECT_THAT(ParseError(R"({"default": "sand", "patches": []})"),
              HasSubstr("terrain_map.default: unknown terrain \"sand\""));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [], "extra": 1})"), HasSubstr("terrain_map.extra: unknown key"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": {}})"), HasSubstr("terrain_map.patches: must be an array"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "ice", "polygon": [[0,0],[1,0],[0,1]]}]})"),
              HasSubstr("terrain_map.patches[0].terrain: unknown terrain \"ice\""));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"polygon": [[0,0],[1,0],[0,1]]}]})"),
              HasSubstr("terrain_map.patches[0].terrain: missing key"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "mud"}]})"),
              HasSubstr("terrain_map.patches[0]: needs exactly one of \"polygon\" and \"rectangle\""));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "mud", "polygon": [[0,0],[1,0],[0,1]],
                             "rectangle": {"min": [0, 0], "max": [1, 1]}}]})"),
              HasSubstr("needs exactly one of"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "mud", "polygon": [[0,0],[1,0]]}]})"),
              HasSubstr("terrain_map.patches[0].polygon: needs at least 3"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "mud", "polygon": [[0,0],[1,1],[1,0],[0,1]]}]})"),
              HasSubstr("terrain_map.patches[0].polygon: not a simple polygon"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "mud", "polygon": [[0,0],[1,"x"],[0,1]]}]})"),
              HasSubstr("terrain_map.patches[0].polygon[1]: must be an array of 2 numbers"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "mud", "rectangle": {"min": [0, 0], "max": [1, 0]}}]})"),
              HasSubstr("terrain_map.patches[0].rectangle: min must be below max"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "mud", "rectangle": {"min": [0, 0]}}]})"),
              HasSubstr("terrain_map.patches[0].rectangle.max: missing key"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "mud", "rectangle": {"min": [0, 0], "max": [1, 1], "z": 0}}]})"),
              HasSubstr("terrain_map.patches[0].rectangle.z: unknown key"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [{"terrain": "mud", "polygon": [[0,0],[1,0],[0,1]], "name": "a"}]})"),
              HasSubstr("terrain_map.patches[0].name: unknown key"));
  EXPECT_THAT(ParseError(R"({"default": "grass", "patches": [3]})"), HasSubstr("terrain_map.patches[0]: must be an object"));
  EXPECT_THAT(ParseError("{"), HasSubstr("scenario.json: invalid JSON"));
}

}  // namespace
}  // namespace rowloc::sim

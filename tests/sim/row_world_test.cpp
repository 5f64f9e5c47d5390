// RowWorld: exact row geometry (straight, arc, S-curve), canopy variation, gaps, the true row
// map and its GeoJSON round trip, determinism, world files and their errors.
#include "rowloc/sim/row_world.hpp"

#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <stdexcept>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;

std::filesystem::path WorldFile(const std::string& name) {
  return test::SourceDir() / "config" / "worlds" / (name + ".json");
}

RowWorldParams Arc(double radius_m) {
  RowWorldParams p;
  p.row_count = 4;
  p.row_length_m = 30.0;
  p.curvature = RowCurvature::kArc;
  p.curvature_radius_m = radius_m;
  p.canopy.roughness_amplitude_m = 0.01;
  return p;
}

TEST(RowWorld, DefaultsEqualTheShippedVineyard002) {
  const RowWorldParams file = LoadRowWorldParams(WorldFile("vineyard-002"));
  const RowWorldParams code;
  EXPECT_EQ(file.name, code.name);
  EXPECT_EQ(file.seed, code.seed);
  EXPECT_EQ(file.origin.latitude_deg, code.origin.latitude_deg);
  EXPECT_EQ(file.origin.longitude_deg, code.origin.longitude_deg);
  EXPECT_EQ(file.origin.altitude_m, code.origin.altitude_m);
  EXPECT_EQ(file.row_count, code.row_count);
  EXPECT_EQ(file.row_spacing_m, code.row_spacing_m);
  EXPECT_EQ(file.row_length_m, code.row_length_m);
  EXPECT_EQ(file.heading_rad, code.heading_rad);
  EXPECT_EQ(file.curvature, code.curvature);
  EXPECT_EQ(file.curvature_radius_m, code.curvature_radius_m);
  EXPECT_TRUE(file.gaps.empty());
  EXPECT_EQ(file.canopy, code.canopy);
  EXPECT_EQ(file.terrain, code.terrain);
}

TEST(RowWorld, ShippedWorldsLoad) {
  for (const char* name : {"vineyard-002", "vineyard-002-rough", "curved"}) {
    SCOPED_TRACE(name);
    const RowWorld world(LoadRowWorldParams(WorldFile(name)));
    EXPECT_EQ(world.params().name, name);
    EXPECT_FALSE(world.OutlineAt(1.0, 0.05).empty());
  }
  const RowWorldParams curved = LoadRowWorldParams(WorldFile("curved"));
  EXPECT_EQ(curved.curvature, RowCurvature::kSCurve);
  ASSERT_EQ(curved.gaps.size(), 3u);
  EXPECT_EQ(curved.gaps[0], (RowGap{1, 12.0, 14.5}));
  EXPECT_EQ(curved.curvature_radius_m, 40.0);
  EXPECT_NE(curved.terrain.grade_east, 0.0);
}

TEST(RowWorld, StraightRowsAreParallelAtTheirSpacing) {
  RowWorldParams p;
  p.heading_rad = 0.3;
  const RowWorld world(p);
  const Eigen::Vector2d along(std::cos(0.3), std::sin(0.3)), left(-std::sin(0.3), std::cos(0.3));
  for (int k = 0; k < p.row_count; ++k)
    for (double s = 0; s <= p.row_length_m; s += 3.7) {
      EXPECT_LT((world.RowCentre(k, s) - (s * along + k * 2.5 * left)).norm(), 1e-12);
      EXPECT_EQ(world.CurvatureAt(s), 0.0);
    }
}

TEST(RowWorld, ArcOutlineIsAtTheAnalyticRadiusPlusMinusHalfWidth) {
  for (const double radius_m : {40.0, -25.0}) {
    SCOPED_TRACE(radius_m);
    const RowWorld world(Arc(radius_m));
    const Eigen::Vector2d centre(0.0, radius_m);  // heading 0 from the origin: centre on the left for R > 0
    const double sign = radius_m > 0 ? 1.0 : -1.0;
    for (int k = 0; k < 4; ++k)
      for (double s = 0; s <= 30.0; s += 1.3) {
        const double r_centre = std::abs(radius_m - k * 2.5);
        EXPECT_NEAR((world.RowCentre(k, s) - centre).norm(), r_centre, 1e-9);
        const Eigen::Vector2d n = world.ReferenceNormal(s);
        const Eigen::Vector2d left = world.RowCentre(k, s) + world.LeftHalfWidth(k, s) * n;
        const Eigen::Vector2d right = world.RowCentre(k, s) - world.RightHalfWidth(k, s) * n;
        EXPECT_NEAR((left - centre).norm(), r_centre - sign * world.LeftHalfWidth(k, s), 1e-9);
        EXPECT_NEAR((right - centre).norm(), r_centre + sign * world.RightHalfWidth(k, s), 1e-9);
      }
    // The sampled outline vertices lie on those circles too (left edge first, forward).
    const auto parts = world.OutlineAt(1.0, 0.5);
    ASSERT_EQ(parts.size(), 4u);
    const std::size_t n = parts[2].polygon_m.size() / 2;  // stations per edge
    for (std::size_t i = 0; i < n; ++i) {
      const double s = 30.0 * static_cast<double>(i) / static_cast<double>(n - 1);
      EXPECT_NEAR((parts[2].polygon_m[i] - centre).norm(), std::abs(radius_m - 5.0) - sign * world.LeftHalfWidth(2, s),
                  1e-9);
    }
  }
}

TEST(RowWorld, SCurveIsContinuousUnitSpeedAndKeepsTheSpacing) {
  RowWorldParams p;
  p.curvature = RowCurvature::kSCurve;
  p.curvature_radius_m = 30.0;
  p.row_length_m = 40.0;
  const RowWorld world(p);
  EXPECT_EQ(world.CurvatureAt(10.0), 1.0 / 30.0);
  EXPECT_EQ(world.CurvatureAt(30.0), -1.0 / 30.0);
  const double h = 1e-4;
  for (double s = h; s < 40.0 - h; s += 0.77) {
    EXPECT_NEAR((world.ReferencePoint(s + h) - world.ReferencePoint(s - h)).norm() / (2 * h), 1.0, 1e-7);
    for (int k = 0; k + 1 < p.row_count; ++k)
      EXPECT_NEAR((world.RowCentre(k + 1, s) - world.RowCentre(k, s)).norm(), 2.5, 1e-9);
  }
  EXPECT_LT((world.ReferencePoint(20.0 - 1e-9) - world.ReferencePoint(20.0 + 1e-9)).norm(), 1e-8);
  // Heading returns to the start heading at the end of the S.
  EXPECT_LT((world.ReferenceNormal(40.0) - world.ReferenceNormal(0.0)).norm(), 1e-12);
}

TEST(RowWorld, CanopyVariesWithinItsBoundsAndRoughnessDiffersPerSide) {
  RowWorldParams p;
  p.canopy.roughness_amplitude_m = 0.015;
  const RowWorld world(p);
  RowWorldParams smooth_p = p;
  smooth_p.canopy.roughness_amplitude_m = 0.0;
  const RowWorld smooth(smooth_p);
  double max_rough = 0.0, min_w = 1.0, max_w = 0.0;
  bool sides_differ = false;
  for (double s = 0; s <= 50.0; s += 0.011) {
    const double wl = world.LeftHalfWidth(1, s), wr = world.RightHalfWidth(1, s), w0 = smooth.LeftHalfWidth(1, s);
    max_rough = std::max(max_rough, std::abs(wl - w0));
    min_w = std::min(min_w, w0);
    max_w = std::max(max_w, w0);
    sides_differ = sides_differ || std::abs(wl - wr) > 1e-3;
    EXPECT_LE(std::abs(w0 - 0.25), 0.03 + 1e-12);
    EXPECT_LE(std::abs(world.BandBottom(1, s) - 0.5), 0.1 + 1e-12);
    EXPECT_LE(std::abs(world.BandTop(1, s) - 1.8), 0.1 + 1e-12);
  }
  EXPECT_LE(max_rough, 0.015 + 1e-12);
  EXPECT_GT(max_rough, 0.005);
  EXPECT_GT(max_w - min_w, 0.02);  // the width really varies
  EXPECT_TRUE(sides_differ);
}

TEST(RowWorld, GapsAndBandSplitTheRowIntoParts) {
  RowWorldParams p;
  p.row_count = 2;
  p.row_length_m = 20.0;
  p.gaps = {{1, 5.0, 7.25}, {1, 12.0, 20.0}};
  const RowWorld world(p);
  EXPECT_FALSE(world.HasCanopy(1, 6.0, 1.0));
  EXPECT_TRUE(world.HasCanopy(1, 5.0, 1.0));  // gap ends carry canopy
  EXPECT_TRUE(world.HasCanopy(0, 6.0, 1.0));
  EXPECT_FALSE(world.HasCanopy(0, 6.0, 0.3));  // below the band
  EXPECT_FALSE(world.HasCanopy(0, 6.0, 2.0));  // above it
  const geometry::RowMap map = world.TrueRowMap(1.0, 0.1);
  ASSERT_EQ(map.rows.size(), 3u);
  EXPECT_EQ(map.rows[0].id, "row-1");
  EXPECT_EQ(map.rows[1].id, "row-2.part-1");
  EXPECT_EQ(map.rows[2].id, "row-2.part-2");
  // Part 1 ends exactly at the gap start, part 2 spans [7.25, 12].
  const auto& part1 = map.rows[1].points_m;
  const Eigen::Vector2d end_left = world.RowCentre(1, 5.0) + world.LeftHalfWidth(1, 5.0) * world.ReferenceNormal(5.0);
  EXPECT_LT((part1[part1.size() / 2 - 1] - end_left).norm(), 1e-12);
  const auto& part2 = map.rows[2].points_m;
  EXPECT_NEAR(part2.front().x(), 7.25, 1e-12);
  EXPECT_NEAR(part2[part2.size() / 2 - 1].x(), 12.0, 1e-12);
  EXPECT_FALSE(geometry::ValidateRowMap(map).has_value());
  EXPECT_THROW(world.TrueRowMap(3.0, 0.1), std::invalid_argument);  // above every canopy
  EXPECT_THROW(world.OutlineAt(1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(world.OutlineAt(NAN, 0.1), std::invalid_argument);
  RowWorldParams huge;
  huge.row_count = 1000;
  huge.row_length_m = 10000.0;
  huge.row_spacing_m = 3.0;
  EXPECT_THROW(RowWorld(huge).OutlineAt(1.0, 1e-3), std::invalid_argument);  // 1e10 stations
  EXPECT_THROW(world.RowCentre(2, 1.0), std::out_of_range);
}

TEST(RowWorld, HeightNearTheBandBottomKeepsOnlyTheStationsWithCanopy) {
  const RowWorld world{RowWorldParams{}};  // straight along +East: x is the station
  const double h = 0.5;                    // the mean band bottom: the band crosses it
  const auto parts = world.OutlineAt(h, 0.05);
  std::size_t split_rows = 0;
  for (int k = 0; k < 6; ++k) {
    std::vector<const OutlinePart*> row_parts;
    for (const auto& p : parts)
      if (p.row == k) row_parts.push_back(&p);
    if (row_parts.size() > 1) ++split_rows;
    for (std::size_t j = 0; j < row_parts.size(); ++j) {
      const auto& poly = row_parts[j]->polygon_m;
      const double first = poly.front().x(), last = poly[poly.size() / 2 - 1].x();
      for (std::size_t i = 0; i < poly.size() / 2; ++i) EXPECT_TRUE(world.HasCanopy(k, poly[i].x(), h));
      if (j + 1 < row_parts.size()) {  // between two parts there is no canopy at that height
        const double next = row_parts[j + 1]->polygon_m.front().x();
        EXPECT_FALSE(world.HasCanopy(k, 0.5 * (last + next), h));
      }
      EXPECT_LT(first, last);
    }
  }
  EXPECT_GT(split_rows, 0u);
}

TEST(RowWorld, TrueRowMapSurvivesTheGeoJsonRoundTrip) {
  const RowWorld world(LoadRowWorldParams(WorldFile("curved")));
  const geometry::RowMap map = world.TrueRowMap(1.0, 0.05);
  test::ScratchDir dir;
  mapio::WriteRowMapGeoJson(map, dir / "truth.geojson");
  const geometry::RowMap back = mapio::ReadRowMapGeoJson(dir / "truth.geojson");
  ASSERT_EQ(back.rows.size(), map.rows.size());
  EXPECT_EQ(back.origin.latitude_deg, map.origin.latitude_deg);
  for (std::size_t i = 0; i < map.rows.size(); ++i) {
    EXPECT_EQ(back.rows[i].id, map.rows[i].id);
    EXPECT_TRUE(back.rows[i].closed);
    ASSERT_EQ(back.rows[i].points_m.size(), map.rows[i].points_m.size());
    for (std::size_t j = 0; j < map.rows[i].points_m.size(); ++j)
      EXPECT_LT((back.rows[i].points_m[j] - map.rows[i].points_m[j]).norm(), 1e-6);
  }
}

TEST(RowWorld, SameSeedSameOutlinesOtherSeedOther) {
  const RowWorldParams p = LoadRowWorldParams(WorldFile("curved"));
  const auto a = RowWorld(p).OutlineAt(1.2, 0.05);
  const auto b = RowWorld(p).OutlineAt(1.2, 0.05);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].polygon_m, b[i].polygon_m);
  RowWorldParams q = p;
  q.seed += 1;
  const auto c = RowWorld(q).OutlineAt(1.2, 0.05);
  ASSERT_FALSE(c.empty());
  EXPECT_NE(a[0].polygon_m, c[0].polygon_m);
}

TEST(RowWorld, SampledOutlineIsWithinTheToleranceOfTheTrueEdges) {
  const RowWorld world(LoadRowWorldParams(WorldFile("curved")));
  const double tolerance_m = 1e-4;
  const double step = world.StepForTolerance(tolerance_m);
  EXPECT_NEAR(step, std::sqrt(8.0 * tolerance_m / world.OutlineCurvatureBound()), 1e-15);
  const auto parts = world.OutlineAt(1.0, step);
  ASSERT_FALSE(parts.empty());
  ASSERT_EQ(parts[0].row, 0);
  const auto& polygon = parts[0].polygon_m;
  std::vector<geometry::SegmentIndex::Entry> left_edge;
  for (std::size_t i = 0; i + 1 < polygon.size() / 2; ++i) left_edge.push_back({{polygon[i], polygon[i + 1]}, 0, i});
  const geometry::SegmentIndex index(left_edge);
  double max_error_m = 0.0;
  for (double s = 25.0; s <= 35.0; s += 0.0003) {  // across the S-curve's inflection at 30 m
    const Eigen::Vector2d truth = world.RowCentre(0, s) + world.LeftHalfWidth(0, s) * world.ReferenceNormal(s);
    max_error_m = std::max(max_error_m, index.Nearest(truth, 1).front().first);
  }
  EXPECT_LT(max_error_m, tolerance_m);
  EXPECT_GT(max_error_m, 0.0);
  EXPECT_THROW(world.StepForTolerance(0.0), std::invalid_argument);
  EXPECT_THROW(world.StepForTolerance(1e-9), std::invalid_argument);  // step would be < 0.1 mm
}

std::string LoadError(const std::string& text) {
  try {
    ParseRowWorldParams(text, "w.json");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

TEST(RowWorld, BadWorldFilesGiveClearErrors) {
  std::ifstream in(WorldFile("vineyard-002"));
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    const auto pos = t.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    return t.replace(pos, from.size(), to);
  };
  EXPECT_EQ(LoadError(good), "no error");
  EXPECT_THAT(LoadError("{"), HasSubstr("w.json: JSON syntax error"));
  EXPECT_THAT(LoadError("[]"), HasSubstr("w.json: top level: must be a JSON object"));
  EXPECT_THAT(LoadError(with("\"seed\": 2,", "")), HasSubstr("w.json: seed: missing"));
  EXPECT_THAT(LoadError(with("\"seed\": 2,", "\"seed\": 2, \"colour\": 1,")), HasSubstr("w.json: colour: unknown key"));
  EXPECT_THAT(LoadError(with("\"count\": 6", "\"count\": \"six\"")), HasSubstr("w.json: rows.count: must be an integer"));
  EXPECT_THAT(LoadError(with("\"spacing_m\": 2.5", "\"spacing_m\": null")), HasSubstr("rows.spacing_m: must be a number"));
  EXPECT_THAT(LoadError(with("\"straight\"", "\"zigzag\"")), HasSubstr("curvature.type: must be \"straight\""));
  EXPECT_THAT(LoadError(with("\"straight\", \"radius_m\": 0.0", "\"arc\", \"radius_m\": 5.0")),
              HasSubstr("w.json: curvature.radius_m is too small"));
  EXPECT_THAT(LoadError(with("\"gaps\": []", "\"gaps\": [{\"row\": 9, \"start_m\": 1, \"end_m\": 2}]")),
              HasSubstr("gaps[0].row must be in [0, rows.count)"));
  EXPECT_THAT(LoadError(with("\"gaps\": []", "\"gaps\": [{\"row\": 0, \"start_m\": 3, \"end_m\": 2}]")),
              HasSubstr("gaps[0]: need 0 <= start_m, start_m + 0.001 <= end_m <= rows.length_m"));
  EXPECT_THAT(LoadError(with("\"gaps\": []", "\"gaps\": [{\"row\": 0, \"start_m\": 3, \"end_m\": 51}]")),
              HasSubstr("gaps[0]: need"));
  EXPECT_THAT(LoadError(with("\"gaps\": []", "\"gaps\": [{\"row\": 0, \"start_m\": 3, \"end_m\": 5},"
                                            " {\"row\": 0, \"start_m\": 5.0005, \"end_m\": 6}]")),
              HasSubstr("w.json: gaps[1] and gaps[0] overlap or are closer than 1 mm"));
  EXPECT_EQ(LoadError(with("\"gaps\": []", "\"gaps\": [{\"row\": 0, \"start_m\": 3, \"end_m\": 5},"
                                          " {\"row\": 1, \"start_m\": 4, \"end_m\": 6}]")),
            "no error");
  EXPECT_THAT(LoadError(with("\"gaps\": []", "\"gaps\": [{\"row\": 0}]")), HasSubstr("w.json: gaps[0].end_m: missing"));
  EXPECT_THAT(LoadError(with("\"half_width_m\": 0.25", "\"half_width_m\": 1.3")), HasSubstr("spacing_m / 2"));
  EXPECT_THAT(LoadError(with("\"top_m\": 1.8", "\"top_m\": 0.6")), HasSubstr("band must never be empty"));
  EXPECT_THAT(LoadError(with("\"grade_east\": 0.0", "\"grade_east\": 2.0")), HasSubstr("terrain.grade_east"));
  EXPECT_THAT(LoadError(with("\"latitude_deg\": 45.0703", "\"latitude_deg\": 95")), HasSubstr("w.json: origin: "));
  EXPECT_THAT(LoadError(with("\"seed\": 2", "\"seed\": -2")), HasSubstr("w.json: seed: must be >= 0"));
  try {
    LoadRowWorldParams("/nonexistent/world.json");
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("/nonexistent/world.json: cannot open"));
  }
}

TEST(RowWorld, ConstructorRejectsBadParameters) {
  RowWorldParams p;
  p.row_count = 0;
  EXPECT_THROW(RowWorld{p}, std::invalid_argument);
  p = {};
  p.name.clear();
  EXPECT_THROW(RowWorld{p}, std::invalid_argument);
  p = {};
  p.canopy.roughness_max_wavelength_m = 0.05;
  EXPECT_THROW(RowWorld{p}, std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::sim

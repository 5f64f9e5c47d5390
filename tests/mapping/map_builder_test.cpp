// BuildRowMap and RunMapBuild: rows over a sloped field, the same map from UTM coordinates, no
// rows, georeference parsing, the output files, and clear errors.
#include "rowloc/mapping/map_builder.hpp"

#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/mapping/canopy_occupancy_map.hpp"
#include "rowloc/mapping/map_comparison.hpp"
#include "synthetic_rows.hpp"
#include "test_support.hpp"

#include <GeographicLib/UTMUPS.hpp>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

using ::testing::HasSubstr;

const geometry::GeoOrigin kOrigin{45.0703, 7.6869, 240.0};

test::SyntheticField SlopedField() {
  test::SyntheticField field;
  field.rows = {{0, 15, 0.0, 0.25}, {0, 6, 2.5, 0.25}, {7.5, 15, 2.5, 0.25}, {0, 15, 5.0, 0.25}};
  field.grade_x = 0.1;
  field.grade_y = 0.05;
  return field;
}

/// The true map of a field: rectangles (x0..x1, y -+ half_width) at any height.
geometry::RowMap TrueMap(const test::SyntheticField& field) {
  geometry::RowMap map;
  map.origin = kOrigin;
  int k = 0;
  for (const auto& r : field.rows) {
    std::string id = "t";  // (not "t" + std::to_string(k): GCC 12's false -Wrestrict)
    id += std::to_string(k++);
    map.rows.push_back(geometry::Row{id,
                                     {{r.x0, r.y - r.half_width}, {r.x1, r.y - r.half_width},
                                      {r.x1, r.y + r.half_width}, {r.x0, r.y + r.half_width}},
                                     true, 0.0});
  }
  return map;
}

/// The field's cloud written to DIR/survey.pcd, and a request to build it into DIR/out.
MapBuildRequest SurveyRequest(const test::SyntheticField& field, const test::ScratchDir& dir) {
  WritePointCloud(field.Cloud(), dir / "survey.pcd");
  MapBuildRequest request;
  request.survey_path = dir / "survey.pcd";
  request.output_dir = dir / "out";
  request.georeference = Georeference::Local(kOrigin);
  return request;
}

TEST(MapBuilderTest, RowsOverASlopedFieldMatchTheTruth) {
  const test::SyntheticField field = SlopedField();
  const MapBuildResult result = BuildRowMap(field.Cloud(), MapBuildConfig{}, Georeference::Local(kOrigin));
  ASSERT_TRUE(result.map.has_value()) << result.message;
  EXPECT_EQ(result.rows, 3U);
  ASSERT_EQ(result.map->rows.size(), 4U);
  EXPECT_EQ(result.map->rows[0].id, "row-1");
  EXPECT_EQ(result.map->rows[1].id, "row-2.part-1");  // the gap is bridged: one row, two parts
  EXPECT_EQ(result.map->rows[2].id, "row-2.part-2");
  EXPECT_EQ(result.map->rows[3].id, "row-3");
  EXPECT_EQ(result.map->origin.latitude_deg, kOrigin.latitude_deg);
  const MapComparison c = CompareRowMaps(*result.map, TrueMap(field));
  EXPECT_TRUE(c.missed.empty());
  EXPECT_TRUE(c.invented.empty());
  EXPECT_LT(c.p95_m, 0.01);
  EXPECT_LT(c.max_m, 0.03);
  // Every stage is reported.
  ASSERT_GE(result.stages.size(), 8U);
  EXPECT_EQ(result.stages.front().name, "tiles: steps 1-3");
  EXPECT_EQ(result.stages[1].name, "clean: voxel downsampling");
}

TEST(MapBuilderTest, EachPartStatesItsOutlinesAccuracy) {
  // Each part states its outline's accuracy in the map (outline_sigma_m, which the filter adds to
  // the range noise): about zero on clean faces, grows with leafy ones, of the order of the error
  // measured against the truth, and the same in the report.
  double previous = -1.0;
  for (const double roughness : {0.0, 0.01, 0.03}) {
    SCOPED_TRACE(roughness);
    test::SyntheticField field = SlopedField();
    field.face_roughness_m = roughness;
    const MapBuildResult result = BuildRowMap(field.Cloud(), MapBuildConfig{}, Georeference::Local(kOrigin));
    ASSERT_TRUE(result.map.has_value()) << result.message;
    ASSERT_EQ(result.parts.size(), result.map->rows.size());
    for (std::size_t i = 0; i < result.parts.size(); ++i) {
      EXPECT_LT(result.map->rows[i].outline_sigma_m, std::max(0.002, roughness));
      EXPECT_NEAR(result.map->rows[i].outline_sigma_m, result.parts[i].outline_sigma_m, 1e-4);
    }
    const MapComparison c = CompareRowMaps(*result.map, TrueMap(field));
    EXPECT_GT(c.stated_sigma_rms_m, previous);
    previous = c.stated_sigma_rms_m;
    if (roughness > 0.0) {
      EXPECT_GT(c.stated_sigma_rms_m, 0.5 * c.built_to_truth_rms_m);
      EXPECT_LT(c.stated_sigma_rms_m, 2.0 * c.built_to_truth_rms_m);
    }
  }
}

TEST(MapBuilderTest, UtmCloudGivesTheSameMapAsTheLocalOne) {
  // The field placed in UTM zone 32N at the origin: float32 would round its northings to 0.5 m.
  const test::SyntheticField field = SlopedField();
  double easting = 0.0;
  double northing = 0.0;
  int zone = 0;
  bool north = true;
  GeographicLib::UTMUPS::Forward(kOrigin.latitude_deg, kOrigin.longitude_deg, zone, north, easting, northing);
  ASSERT_EQ(zone, 32);
  PointCloud utm = field.Cloud();
  for (auto& p : utm.points_m) p += Eigen::Vector3d(easting, northing, 240.0);
  const MapBuildResult result = BuildRowMap(utm, MapBuildConfig{}, Georeference::FromCrs("EPSG:32632"));
  ASSERT_TRUE(result.map.has_value()) << result.message;
  ASSERT_EQ(result.map->rows.size(), 4U);
  // Compared in the true map's frame (through WGS84): the UTM grid is rotated against true north
  // (meridian convergence ~0.9 deg here) and scaled by ~0.9996, so the built map is the truth
  // turned by the convergence angle about the origin and scaled.
  double gamma = 0.0;
  double k = 0.0;
  double x = 0.0;
  double y = 0.0;
  GeographicLib::UTMUPS::Forward(kOrigin.latitude_deg, kOrigin.longitude_deg, zone, north, x, y, gamma, k);
  geometry::RowMap truth = TrueMap(field);
  const mapio::LocalFrame frame(kOrigin);
  for (auto& row : truth.rows) {
    for (auto& p : row.points_m) {
      double lat = 0.0;
      double lon = 0.0;
      GeographicLib::UTMUPS::Reverse(32, true, easting + p.x(), northing + p.y(), lat, lon);
      p = frame.ToEnu(lat, lon, 240.0).head<2>();
    }
  }
  const MapComparison c = CompareRowMaps(*result.map, truth);
  EXPECT_TRUE(c.missed.empty());
  EXPECT_TRUE(c.invented.empty());
  EXPECT_LT(c.p95_m, 0.01);
  EXPECT_GT(std::abs(gamma), 0.5);  // the rotation is real: a plain offset would be off by decimetres
}

TEST(MapBuilderTest, RowsSeenFromOneSideTakeTheirWidthFromTheCanopyTop) {
  test::SyntheticField field = SlopedField();
  field.one_sided = true;
  const MapBuildResult result = BuildRowMap(field.Cloud(), MapBuildConfig{}, Georeference::Local(kOrigin));
  ASSERT_TRUE(result.map.has_value()) << result.message;
  ASSERT_EQ(result.map->rows.size(), 4U);
  EXPECT_EQ(result.one_sided_parts, 4U);
  EXPECT_EQ(result.outlines_failed, 0U);
  EXPECT_THAT(result.message, HasSubstr("4 parts seen from one side only"));
  for (const PartReport& part : result.parts) {
    EXPECT_TRUE(part.one_sided);
    EXPECT_NEAR(part.width_m, 0.5, 0.03) << part.id;
    EXPECT_LT(part.width_spread_m, 0.02) << part.id;
  }
  const MapComparison c = CompareRowMaps(*result.map, TrueMap(field));
  EXPECT_TRUE(c.missed.empty());
  EXPECT_TRUE(c.invented.empty());
  EXPECT_LT(c.p95_m, 0.02);
  EXPECT_LT(c.max_m, 0.05);
  // With the route off, the same parts are single faces: reported, not mapped.
  MapBuildConfig off;
  off.outline.one_sided_max_width_m = 0.0;
  const MapBuildResult faces = BuildRowMap(field.Cloud(), off, Georeference::Local(kOrigin));
  EXPECT_FALSE(faces.map.has_value());
  EXPECT_EQ(faces.outlines_failed, 4U);
  EXPECT_THAT(faces.message, HasSubstr("single canopy faces"));
}

TEST(MapBuilderTest, NoRowsIsAResultNotAnError) {
  test::SyntheticField flat;
  flat.rows = {{0, 10, 0.0, 0.25}};
  flat.top = 0.6;  // canopy below the band (1 m +- 0.15 m)
  const MapBuildResult result = BuildRowMap(flat.Cloud(), MapBuildConfig{}, Georeference::Local(kOrigin));
  EXPECT_FALSE(result.map.has_value());
  EXPECT_EQ(result.rows, 0U);
  EXPECT_THAT(result.message, HasSubstr("no rows found"));
  EXPECT_THROW(BuildRowMap(PointCloud{}, MapBuildConfig{}, Georeference::Local(kOrigin)), std::invalid_argument);
  MapBuildConfig bad;
  bad.band.band_half_width_m = 0.0;
  EXPECT_THROW(BuildRowMap(flat.Cloud(), bad, Georeference::Local(kOrigin)), std::invalid_argument);
}

TEST(MapBuilderTest, GeoreferenceParsing) {
  const Georeference north = Georeference::FromCrs("EPSG:32632");
  EXPECT_EQ(north.kind, Georeference::Kind::kUtm);
  EXPECT_EQ(north.utm_zone, 32);
  EXPECT_TRUE(north.utm_north);
  const Georeference south = Georeference::FromCrs("epsg:32701");
  EXPECT_EQ(south.utm_zone, 1);
  EXPECT_FALSE(south.utm_north);
  EXPECT_EQ(south.Describe(), "EPSG:32701 (UTM 1S)");
  for (const char* bad : {"EPSG:32600", "EPSG:32661", "EPSG:4326", "32632", "EPSG:3263x", ""}) {
    EXPECT_THROW(Georeference::FromCrs(bad), std::invalid_argument) << bad;
  }
  EXPECT_THROW(Georeference::Local({91.0, 0.0, 0.0}), std::invalid_argument);
}

TEST(MapBuilderTest, RunMapBuildWritesEveryOutput) {
  test::ScratchDir dir;
  MapBuildRequest request = SurveyRequest(SlopedField(), dir);
  const MapBuildResult result = RunMapBuild(request);
  ASSERT_TRUE(result.map.has_value());
  const geometry::RowMap back = mapio::ReadRowMapGeoJson(dir / "out/row-map.geojson");
  EXPECT_EQ(back.rows.size(), 4U);
  for (const char* name : {"dtm.json", "report.txt", "report.json", "map.svg"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / name)) << name;
  }
  std::stringstream report;
  report << std::ifstream(dir / "out/report.txt").rdbuf();
  EXPECT_THAT(report.str(), HasSubstr("3 rows (4 parts"));
  EXPECT_THAT(report.str(), HasSubstr("data reduction"));
  // The JSON report: one entry per part with its width, measured from both faces here.
  const nlohmann::json json = nlohmann::json::parse(std::ifstream(dir / "out/report.json"));
  ASSERT_EQ(json.at("row_parts").size(), 4U);
  for (const auto& part : json.at("row_parts")) {
    EXPECT_FALSE(part.at("one_sided").get<bool>());
    EXPECT_NEAR(part.at("width_m").get<double>(), 0.5, 0.02);
  }
  EXPECT_EQ(json.at("one_sided_parts").get<int>(), 0);
  std::stringstream svg;
  svg << std::ifstream(dir / "out/map.svg").rdbuf();
  EXPECT_THAT(svg.str(), HasSubstr("<svg"));
  EXPECT_THAT(svg.str(), HasSubstr("<polygon"));
  EXPECT_THAT(svg.str(), HasSubstr("</svg>"));
  EXPECT_EQ(result.stages.front().name, "read and tile");
  EXPECT_EQ(result.stages.back().name, "write");
  EXPECT_FALSE(std::filesystem::exists(dir / "out/canopy.bt"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out/.rowloc-tiles"));  // the spilled tiles are gone
}

TEST(MapBuilderTest, EveryPartGetsALoftedMeshThatAgreesWithItsOutline) {
  // The sloped field's boxes are 1.3 m tall (0.5-1.8 m above the ground): the four mesh levels
  // (0.6-1.6 m) all see both faces; the mesh cut at h_ref = 1 m (between two levels) lies on the
  // part's outline within the interpolation of two equal outlines, i.e. within a centimetre.
  test::ScratchDir dir;
  const test::SyntheticField field = SlopedField();
  MapBuildRequest request = SurveyRequest(field, dir);
  const MapBuildResult result = RunMapBuild(request);
  ASSERT_EQ(result.parts.size(), 4U);
  std::size_t triangles = 0;
  for (const PartReport& part : result.parts) {
    EXPECT_EQ(part.mesh_levels, 4) << part.id;
    ASSERT_TRUE(part.mesh_slice_max_m.has_value()) << part.id;
    EXPECT_LT(*part.mesh_slice_max_m, 0.01) << part.id;
    triangles += part.mesh_triangles;
  }
  EXPECT_EQ(result.meshes.triangles.size(), triangles);
  EXPECT_FALSE(ValidateTriangleMesh(result.meshes).has_value());
  // Heights are the terrain plus h: every vertex between 0.6 and 1.6 m above the sloped ground.
  for (const auto& v : result.meshes.vertices_m) {
    const double h = v.z() - field.Ground(v.x(), v.y());
    EXPECT_GT(h, 0.6 - 0.03);
    EXPECT_LT(h, 1.6 + 0.03);
  }
  // meshes.ply reads back (PCL) with every vertex.
  const PointCloud back = ReadPointCloud(dir / "out/meshes.ply");
  EXPECT_EQ(back.points_m.size(), result.meshes.vertices_m.size());
  // No levels, no meshes (and a stale file is removed).
  request.config.mesh.levels = 0;
  const MapBuildResult without = RunMapBuild(request);
  EXPECT_TRUE(without.meshes.triangles.empty());
  EXPECT_FALSE(std::filesystem::exists(dir / "out/meshes.ply"));
  EXPECT_EQ(without.parts.front().mesh_levels, 0);
}

TEST(MapBuilderTest, RunMapBuildWritesTheCanopyOctoMapOnRequest) {
  test::ScratchDir dir;
  const test::SyntheticField field = SlopedField();
  MapBuildRequest request = SurveyRequest(field, dir);
  request.octomap_resolution_m = 0.05;
  const MapBuildResult result = RunMapBuild(request);
  EXPECT_EQ(result.stages.back().name, "octomap: canopy.bt");
  const CanopyOccupancyMap octomap = CanopyOccupancyMap::Load(dir / "out/canopy.bt");
  EXPECT_EQ(octomap.resolution_m(), 0.05);
  // A face of row 1 (y = -0.25) at 1 m above the sloped ground is occupied; the lane and the
  // ground are not (only points above the terrain go into the map).
  EXPECT_TRUE(octomap.IsOccupied({5.0, -0.25, field.Ground(5.0, -0.25) + 1.0}));
  EXPECT_FALSE(octomap.IsOccupied({5.0, 1.25, field.Ground(5.0, 1.25) + 1.0}));
  EXPECT_FALSE(octomap.IsOccupied({5.0, 1.25, field.Ground(5.0, 1.25) + 0.01}));
}

TEST(MapBuilderTest, RunMapBuildNamesAMissingSurvey) {
  test::ScratchDir dir;
  MapBuildRequest request;
  request.survey_path = dir / "nonexistent.pcd";
  request.output_dir = dir / "out";
  request.georeference = Georeference::Local(kOrigin);
  try {
    RunMapBuild(request);
    FAIL() << "expected PointCloudError";
  } catch (const PointCloudError& e) {
    EXPECT_THAT(e.what(), HasSubstr("nonexistent.pcd"));
  }
}

}  // namespace
}  // namespace rowloc::mapping

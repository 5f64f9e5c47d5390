// Steps 1-3 per tile: small tiles give the map and the DTM of one big tile, the thread count does
// not change anything, a tile keeps only its core's products, and a survey with an empty tile in
// the middle still gets a DTM everywhere.
#include "rowloc/mapping/tile_processing.hpp"

#include "rowloc/mapping/map_builder.hpp"
#include "rowloc/mapping/map_comparison.hpp"
#include "synthetic_rows.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace rowloc::mapping {
namespace {

const geometry::GeoOrigin kOrigin{45.0703, 7.6869, 240.0};

test::SyntheticField TwoBlockField() {
  test::SyntheticField field;
  // Rows 31 m long across tile boundaries, a gap between two blocks of rows, a 10 % slope.
  field.rows = {{0, 31, 0.0, 0.25}, {0, 31, 2.5, 0.25}, {0, 12, 5.0, 0.25}, {19, 31, 5.0, 0.25}};
  field.grade_x = 0.1;
  field.grade_y = -0.04;
  field.z0 = 310.0;
  return field;
}

MapBuildConfig WithTiles(double size_m, int threads) {
  MapBuildConfig config;
  config.tiles.size_m = size_m;
  config.tiles.overlap_m = config.terrain.classification_radius_m;
  config.tiles.threads = threads;
  return config;
}

TEST(TileProcessingTest, SmallTilesGiveTheMapAndTerrainOfOneTile) {
  PointCloud cloud = TwoBlockField().Cloud();
  for (auto& p : cloud.points_m) p += Eigen::Vector3d(200.0, 300.0, 0.0);  // inside one 1000 m tile
  const MapBuildResult one = BuildRowMap(cloud, WithTiles(1000.0, 1), Georeference::Local(kOrigin));
  const MapBuildResult many = BuildRowMap(cloud, WithTiles(6.0, 1), Georeference::Local(kOrigin));
  EXPECT_EQ(one.tiles, 1U);
  EXPECT_GE(many.tiles, 12U);
  EXPECT_LT(many.largest_tile_points, cloud.points_m.size() / 3);
  ASSERT_TRUE(one.map && many.map);
  ASSERT_EQ(one.map->rows.size(), many.map->rows.size());
  const MapComparison c = CompareRowMaps(*many.map, *one.map);
  EXPECT_TRUE(c.missed.empty() && c.invented.empty());
  EXPECT_LT(c.p95_m, 0.002);
  EXPECT_LT(c.max_m, 0.01);
  // The DTMs agree on the survey's lattice (same origin and size), within a centimetre.
  ASSERT_EQ(one.terrain->nx(), many.terrain->nx());
  ASSERT_EQ(one.terrain->ny(), many.terrain->ny());
  EXPECT_EQ(one.terrain->origin_m(), many.terrain->origin_m());
  double worst = 0.0;
  for (std::size_t c_index = 0; c_index < one.terrain->heights_m().size(); ++c_index) {
    worst = std::max(worst, std::abs(one.terrain->heights_m()[c_index] - many.terrain->heights_m()[c_index]));
  }
  EXPECT_LT(worst, 0.01);
  // Every point is counted once however many tiles hold it.
  EXPECT_EQ(one.points_in, many.points_in);
  EXPECT_NEAR(static_cast<double>(one.band_points), static_cast<double>(many.band_points), 0.01 * one.band_points);
}

TEST(TileProcessingTest, TheThreadCountChangesNothing) {
  const PointCloud cloud = TwoBlockField().Cloud();
  const MapBuildResult a = BuildRowMap(cloud, WithTiles(12.0, 1), Georeference::Local(kOrigin));
  const MapBuildResult b = BuildRowMap(cloud, WithTiles(12.0, 3), Georeference::Local(kOrigin));
  ASSERT_TRUE(a.map && b.map);
  ASSERT_EQ(a.map->rows.size(), b.map->rows.size());
  for (std::size_t r = 0; r < a.map->rows.size(); ++r) EXPECT_EQ(a.map->rows[r].points_m, b.map->rows[r].points_m);
  EXPECT_EQ(a.terrain->heights_m(), b.terrain->heights_m());
  EXPECT_EQ(b.tile_threads, 3);
}

TEST(TileProcessingTest, ATileKeepsOnlyItsCoresProducts) {
  const test::SyntheticField field = TwoBlockField();
  const PointCloud cloud = field.Cloud();
  TileJob job;
  job.core_m = {{10.0, -2.0}, {20.0, 8.0}};
  job.keep_canopy = true;
  std::vector<Eigen::Vector3d> tile;
  for (const auto& p : cloud.points_m) {
    if (p.x() >= 8.0 && p.x() < 22.0) tile.push_back(p);
  }
  const TileProducts products = ProcessTile(tile, job, MapBuildConfig{});
  EXPECT_EQ(products.points_in, tile.size());
  EXPECT_LT(products.core_points_in, tile.size());
  ASSERT_FALSE(products.band_m.empty());
  for (const auto& p : products.band_m) EXPECT_TRUE(job.core_m.Contains(p));
  for (const auto& p : products.sample_m) EXPECT_TRUE(job.core_m.Contains(p));
  for (const auto& p : products.canopy_m) {
    EXPECT_TRUE(job.core_m.Contains(p.head<2>()));
    EXPECT_GT(p.z() - field.Ground(p.x(), p.y()), MapBuildConfig{}.terrain.ground_tolerance_m - 0.02);
  }
  EXPECT_LE(products.core_cleaned, products.core_points_in);
  EXPECT_GT(products.core_cleaned, products.core_points_in / 2);
  ASSERT_TRUE(products.terrain.has_value());
  EXPECT_LE(products.terrain->origin_m().x(), 8.0);  // the DTM spans the overlap too
}

TEST(TileProcessingTest, AnEmptyTileInTheMiddleGetsTerrainFromItsNeighbours) {
  test::SyntheticField field;
  field.rows = {{0, 30, 0.0, 0.25}};
  field.grade_x = 0.05;
  PointCloud cloud = field.Cloud();
  // Remove every point in x in [12, 18): a hole wider than a tile and its overlaps.
  std::erase_if(cloud.points_m, [](const Eigen::Vector3d& p) { return p.x() >= 12.0 && p.x() < 18.0; });
  MapBuildConfig config = WithTiles(5.0, 1);
  TiledCloud tiled(config.tiles.size_m, config.tiles.overlap_m);
  tiled.Add(cloud.points_m);
  const Eigen::Vector2d offset(std::floor(tiled.min_m().x()), std::floor(tiled.min_m().y()));
  const SurveyProducts survey = ProcessTiles(tiled, offset, config, false);
  ASSERT_TRUE(survey.terrain.has_value());
  for (double x = 0.0; x <= 30.0; x += 0.5) {
    const double h = survey.terrain->HeightAt(Eigen::Vector2d(x, 0.0) - offset);
    EXPECT_TRUE(std::isfinite(h));
    if (x < 11.0 || x > 19.0) {
      EXPECT_NEAR(h, field.Ground(x, 0.0), 0.05) << "x = " << x;
    }
  }
  EXPECT_TRUE(tiled.Tiles().empty());  // every tile released once processed
}

TEST(TileProcessingTest, AnEmptyCloudIsRefused) {
  TiledCloud tiled(10.0, 2.0);
  EXPECT_THROW(ProcessTiles(tiled, Eigen::Vector2d::Zero(), MapBuildConfig{}, false), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::mapping

// TileLayout and TiledCloud: every point in exactly one core and in every tile whose margin holds
// it, the same tiles in memory and spilled to disk, the spill directory's life, bad input.
#include "rowloc/mapping/tiled_cloud.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <system_error>

namespace rowloc::mapping {
namespace {

using ::testing::HasSubstr;

std::vector<Eigen::Vector3d> RandomPoints(std::size_t n, double extent_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, extent_m);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t k = 0; k < n; ++k) points.emplace_back(512000.0 + u(rng), 5012000.0 + u(rng), 200.0 + u(rng) / 10);
  return points;
}

TEST(TileLayoutTest, EveryPointIsInOneCoreAndInTheTilesOfItsMargin) {
  const TileLayout layout(10.0, 2.0, {100.0, -50.0});
  const std::vector<Eigen::Vector3d> points = RandomPoints(2000, 60.0, 1);
  std::vector<TileIndex> holding;
  for (const auto& p3 : points) {
    const Eigen::Vector2d p(p3.x() - 512000.0 + 100.0, p3.y() - 5012000.0 - 50.0);
    const TileIndex core = layout.CoreTile(p);
    EXPECT_TRUE(layout.Core(core).Contains(p));
    holding.clear();
    layout.TilesHolding(p, holding);
    // Exactly the tiles whose core grown by the overlap holds p (checked against the rectangles).
    for (std::int64_t j = core.j - 2; j <= core.j + 2; ++j) {
      for (std::int64_t i = core.i - 2; i <= core.i + 2; ++i) {
        const Rect2 c = layout.Core({i, j});
        const Rect2 grown{c.min_m.array() - 2.0, c.max_m.array() + 2.0};
        const bool listed = std::find(holding.begin(), holding.end(), TileIndex{i, j}) != holding.end();
        EXPECT_EQ(listed, grown.Contains(p)) << "tile " << i << "," << j;
        if (i != core.i || j != core.j) {
          EXPECT_FALSE(c.Contains(p));
        }
      }
    }
    EXPECT_LE(holding.size(), 4U);
  }
}

TEST(TileLayoutTest, BadSizesAreRefused) {
  EXPECT_THROW(TileLayout(0.0, 1.0, {0, 0}), std::invalid_argument);
  EXPECT_THROW(TileLayout(10.0, -1.0, {0, 0}), std::invalid_argument);
  EXPECT_THROW(TileLayout(std::nan(""), 1.0, {0, 0}), std::invalid_argument);
  EXPECT_THROW(TileLayout(10.0, 1.0, {std::numeric_limits<double>::infinity(), 0}), std::invalid_argument);
}

TEST(TiledCloudTest, DiskTilesEqualMemoryTilesAndTheSpillDirectoryIsRemoved) {
  test::ScratchDir dir;
  const std::filesystem::path spill = dir / "spill";
  const std::vector<Eigen::Vector3d> points = RandomPoints(30000, 45.0, 2);  // > kSpillBufferPoints per tile
  TiledCloud memory(20.0, 3.0);
  {
    TiledCloud disk(20.0, 3.0, spill);
    EXPECT_TRUE(std::filesystem::is_directory(spill));
    // Added in uneven chunks: the tiles do not depend on how the points arrive.
    for (std::size_t first = 0; first < points.size(); first += 7001) {
      const std::vector<Eigen::Vector3d> chunk(points.begin() + static_cast<std::ptrdiff_t>(first),
                                               points.begin() + static_cast<std::ptrdiff_t>(std::min(points.size(), first + 7001)));
      disk.Add(chunk);
    }
    memory.Add(points);
    EXPECT_EQ(disk.point_count(), points.size());
    EXPECT_EQ(disk.stored_count(), memory.stored_count());
    EXPECT_GT(disk.stored_count(), points.size());  // the overlaps hold copies
    ASSERT_EQ(disk.Tiles().size(), memory.Tiles().size());
    // 45 m from (512000, 5012000), both multiples of 20 m: 3 x 3 cores.
    EXPECT_EQ(disk.Tiles().size(), 9U);
    EXPECT_EQ(disk.Tiles().front(), (TileIndex{25600, 250600}));
    std::size_t in_cores = 0;
    for (const TileIndex& tile : disk.Tiles()) {
      const std::vector<Eigen::Vector3d> a = disk.Load(tile);
      EXPECT_EQ(a, memory.Load(tile));
      EXPECT_EQ(a.size() <= disk.largest_tile_points(), true);
      const Rect2 core = disk.layout()->Core(tile);
      in_cores += static_cast<std::size_t>(std::count_if(a.begin(), a.end(), [&](const Eigen::Vector3d& p) {
        return core.Contains(p.head<2>());
      }));
      disk.Release(tile);
      EXPECT_TRUE(disk.Load(tile).empty());  // released: nothing left to read
    }
    EXPECT_EQ(in_cores, points.size());
    EXPECT_DOUBLE_EQ(disk.min_m().x(), std::min_element(points.begin(), points.end(), [](auto& a, auto& b) {
                                         return a.x() < b.x();
                                       })->x());
  }
  EXPECT_FALSE(std::filesystem::exists(spill));
}

TEST(TiledCloudTest, RefusesAnExistingDirectoryNonFiniteAndFarPoints) {
  test::ScratchDir dir;
  EXPECT_THROW(TiledCloud(20.0, 3.0, dir.path()), std::system_error);
  EXPECT_TRUE(std::filesystem::exists(dir.path()));  // not removed: it was not ours
  TiledCloud cloud(20.0, 3.0);
  try {
    cloud.Add({{0.0, 0.0, 0.0}, {1.0, std::nan(""), 0.0}});
    FAIL() << "a NaN point was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("point 2 is not finite"));
  }
  EXPECT_THROW(TiledCloud(0.0, 1.0), std::invalid_argument);
  try {
    cloud.Add({{1e300, 0.0, 0.0}});  // finite, but no survey in metres: a tile index would overflow
    FAIL() << "a point at 1e300 m was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("beyond 10^9 m"));
  }
}

TEST(TiledCloudTest, EmptyCloudHasNoTiles) {
  TiledCloud cloud(20.0, 3.0);
  cloud.Add({});
  EXPECT_FALSE(cloud.layout().has_value());
  EXPECT_TRUE(cloud.Tiles().empty());
  EXPECT_EQ(cloud.point_count(), 0U);
  EXPECT_TRUE(cloud.Load({0, 0}).empty());
}

}  // namespace
}  // namespace rowloc::mapping

// BuildTerrainGrid and HeightAt: a tilted plane under box rows (no ground points under them), an
// undulating ground, bilinear lookup, heights above the terrain, bad input.
#include "rowloc/mapping/terrain_grid.hpp"

#include "synthetic_rows.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

TEST(TerrainGridTest, HeightAtIsBilinearBetweenCentresAndHeldOutside) {
  // 2 x 2 cells of 1 m: centres at (0.5, 0.5) ... (1.5, 1.5); heights of the plane z = x + 2 y.
  const TerrainGrid grid(Eigen::Vector2d::Zero(), 1.0, 2, 2, {1.5, 2.5, 3.5, 4.5}, {true, true, true, true});
  EXPECT_NEAR(grid.HeightAt({1.0, 1.0}), 3.0, 1e-12);
  EXPECT_NEAR(grid.HeightAt({0.7, 1.2}), 0.7 + 2.4, 1e-12);
  EXPECT_NEAR(grid.HeightAt({-5.0, 0.5}), 1.5, 1e-12);   // held at the border
  EXPECT_NEAR(grid.HeightAt({9.0, 9.0}), 4.5, 1e-12);
  EXPECT_EQ(grid.GroundCellCount(), 4U);
  EXPECT_THROW(TerrainGrid(Eigen::Vector2d::Zero(), 1.0, 2, 2, {1.0}, {true}), std::invalid_argument);
}

TEST(TerrainGridTest, TiltedPlaneUnderRowsIsFollowed) {
  test::SyntheticField field;
  field.rows = {{0.0, 12.0, 0.0, 0.3}, {0.0, 12.0, 2.5, 0.3}, {0.0, 12.0, 5.0, 0.3}};
  field.grade_x = 0.12;  // 12 % along the rows, -8 % across: one level plane is far off
  field.grade_y = -0.08;
  field.z0 = 300.0;
  const PointCloud cloud = field.Cloud();
  const TerrainGrid dtm = BuildTerrainGrid(cloud, TerrainParams{});
  EXPECT_GT(dtm.GroundCellCount(), 100U);
  // Everywhere, including under the canopy (no ground points there), within 3 cm of the plane.
  double worst = 0.0;
  for (double x = 0.0; x <= 12.0; x += 0.25) {
    for (double y = -1.0; y <= 6.0; y += 0.25) {
      worst = std::max(worst, std::abs(dtm.HeightAt({x, y}) - field.Ground(x, y)));
    }
  }
  EXPECT_LT(worst, 0.03);
  // Canopy bottoms (0.5 m up) are not ground: on a 0.1 m grid, whose cells can lie wholly under
  // the 0.3 m wide row, the cells under row 2's centre line are filled, their neighbours in the
  // lane are ground.
  TerrainParams fine;
  fine.cell_size_m = 0.1;
  fine.min_ground_points = 1;  // the field's ground is sampled every 0.1 m: one point per cell
  const TerrainGrid fine_dtm = BuildTerrainGrid(cloud, fine);
  const auto ground_at = [&fine_dtm](double x, double y) {
    const int i = static_cast<int>((x - fine_dtm.origin_m().x()) / fine_dtm.cell_size_m());
    const int j = static_cast<int>((y - fine_dtm.origin_m().y()) / fine_dtm.cell_size_m());
    return fine_dtm.ground()[static_cast<std::size_t>(j * fine_dtm.nx() + i)];
  };
  EXPECT_FALSE(ground_at(6.05, 2.45));
  EXPECT_FALSE(ground_at(6.05, 2.55));
  EXPECT_TRUE(ground_at(6.05, 1.25));
  // The grid lies on the lattice of multiples of its cell (tiles of one survey share cells).
  EXPECT_DOUBLE_EQ(std::remainder(dtm.origin_m().x(), 0.5), 0.0);
  EXPECT_DOUBLE_EQ(std::remainder(dtm.origin_m().y(), 0.5), 0.0);
}

TEST(TerrainGridTest, UndulatingGroundIsFollowed) {
  // Ground z = 0.3 sin(2 pi x / 15) (+ 5 % across), rows along x.
  PointCloud cloud;
  const auto ground = [](double x, double y) { return 0.3 * std::sin(2.0 * M_PI * x / 15.0) + 0.05 * y; };
  for (double x = 0.0; x <= 30.0; x += 0.1) {
    for (double y = 0.0; y <= 5.0; y += 0.1) {
      const bool canopy = std::abs(y - 2.5) < 0.3;
      if (canopy) {
        if (std::abs(y - 2.5) > 0.25) {  // the faces, 0.5 .. 1.8 m up
          for (double h = 0.5; h <= 1.8; h += 0.1) cloud.points_m.emplace_back(x, y, ground(x, y) + h);
        }
      } else {
        cloud.points_m.emplace_back(x, y, ground(x, y));
      }
    }
  }
  const TerrainGrid dtm = BuildTerrainGrid(cloud, TerrainParams{});
  double worst = 0.0;
  for (double x = 0.5; x <= 29.5; x += 0.1) worst = std::max(worst, std::abs(dtm.HeightAt({x, 2.5}) - ground(x, 2.5)));
  EXPECT_LT(worst, 0.04);
  const std::vector<double> h = HeightsAboveTerrain(cloud, dtm);
  ASSERT_EQ(h.size(), cloud.points_m.size());
  for (std::size_t k = 0; k < cloud.points_m.size(); k += 97) {
    const auto& p = cloud.points_m[k];
    EXPECT_NEAR(h[k], p.z() - dtm.HeightAt(p.head<2>()), 1e-12);
  }
}

TEST(TerrainGridTest, FillFromNeighboursSpreadsTheFilledCellsAndRefusesBadGrids) {
  // A 3 x 1 grid with only its left cell filled: the fill reaches the right end in two passes.
  std::vector<double> heights = {2.0, 0.0, 0.0};
  std::vector<bool> filled = {true, false, false};
  FillFromNeighbours(heights, filled, 3, 1);
  EXPECT_EQ(heights, (std::vector<double>{2.0, 2.0, 2.0}));
  EXPECT_EQ(filled, (std::vector<bool>{true, true, true}));
  std::vector<bool> none = {false, false, false};
  EXPECT_THROW(FillFromNeighbours(heights, none, 3, 1), std::invalid_argument);
  EXPECT_THROW(FillFromNeighbours(heights, filled, 2, 2), std::invalid_argument);
}

TEST(TerrainGridTest, EmptyCloudAndBadParametersThrow) {
  EXPECT_THROW(BuildTerrainGrid(PointCloud{}, TerrainParams{}), std::invalid_argument);
  PointCloud one;
  one.points_m.emplace_back(1.0, 2.0, 3.0);
  TerrainParams bad;
  bad.cell_size_m = 0.0;
  EXPECT_THROW(BuildTerrainGrid(one, bad), std::invalid_argument);
  const TerrainGrid single = BuildTerrainGrid(one, TerrainParams{});
  EXPECT_NEAR(single.HeightAt({1.0, 2.0}), 3.0, 1e-12);
}

}  // namespace
}  // namespace rowloc::mapping

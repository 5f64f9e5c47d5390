// Step 2 of the map build (docs/mapping.md): ground classification and a terrain model (DTM) that follows
// slopes and undulations, with bilinear height lookup; step 3 (height above the terrain) uses it.
//
// Algorithm (BuildTerrainGrid):
//  1. a grid of cell_size_m over the cloud's horizontal extent, on the lattice of multiples of
//     cell_size_m (so that overlapping tiles of one survey share their cells); per cell, its lowest
//     level z_min: the lowest z with at least min_ground_points points within ground_thickness_m
//     above it, so that a stray point below the ground (multipath, an outlier close enough to the
//     ground's points to survive the outlier removal) does not become the ground (the lowest point
//     of each cell if no cell of the cloud has that support);
//  2. per occupied cell, a robust local plane z = a + b dx + c dy fitted by least squares to the
//     z_min of the occupied cells within classification_radius_m; cells more than
//     ground_tolerance_m above the current plane are dropped and the fit repeated (5 times), so the
//     plane settles on the lower envelope (ground) whatever the slope. The cell is ground if its
//     z_min lies within ground_tolerance_m above that plane (canopy bottoms, 0.3 m or more above the
//     ground, are not);
//  3. a ground cell's height is the median of its points within ground_thickness_m of z_min (the
//     lowest level alone is biased low by the noise);
//  4. cells without ground (under the canopy, outside the survey) are filled outward from ground
//     cells, each pass giving an unfilled cell the mean of its filled 8-neighbours, then
//     smoothing_passes 3x3 mean filters smooth the grid.
// Heights are stored at cell centres; HeightAt interpolates bilinearly between centres and holds
// the border value outside the grid.
#pragma once

#include "rowloc/mapping/map_build_config.hpp"
#include "rowloc/mapping/point_cloud.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace rowloc::mapping {

class TerrainGrid {
 public:
  /// A grid of nx * ny cells of edge cell_size_m; cell (i, j) has its centre at
  /// origin + ((i + 0.5) cell, (j + 0.5) cell). heights_m and ground are row-major (index j * nx + i).
  /// Throws std::invalid_argument on sizes that do not match or non-finite heights.
  TerrainGrid(Eigen::Vector2d origin_m, double cell_size_m, int nx, int ny,
              std::vector<double> heights_m, std::vector<bool> ground);

  /// Terrain height at (x, y): bilinear between cell centres, border value outside.
  double HeightAt(const Eigen::Vector2d& xy_m) const;

  const Eigen::Vector2d& origin_m() const { return origin_m_; }
  double cell_size_m() const { return cell_size_m_; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  const std::vector<double>& heights_m() const { return heights_m_; }
  /// Whether a cell's height comes from its own ground points (false: filled).
  const std::vector<bool>& ground() const { return ground_; }
  std::size_t GroundCellCount() const;

 private:
  Eigen::Vector2d origin_m_;
  double cell_size_m_;
  int nx_;
  int ny_;
  std::vector<double> heights_m_;
  std::vector<bool> ground_;
};

/// Builds the DTM of a cloud (algorithm above). Throws std::invalid_argument if the cloud is empty,
/// a parameter is outside its domain (map_build_config.hpp), or the grid would exceed 10^8 cells.
TerrainGrid BuildTerrainGrid(const PointCloud& cloud, const TerrainParams& params);

/// Step 4's fill on its own: every cell with filled[c] == false gets the mean of its filled
/// 8-neighbours, pass after pass, until all are filled (row-major nx * ny). Throws
/// std::invalid_argument if the sizes do not match or no cell is filled.
void FillFromNeighbours(std::vector<double>& heights_m, std::vector<bool>& filled, int nx, int ny);

/// Step 3: the height of every point above the terrain (z - HeightAt(x, y)), in the cloud's order.
std::vector<double> HeightsAboveTerrain(const PointCloud& cloud, const TerrainGrid& terrain);

}  // namespace rowloc::mapping

// Steps 1-3 of the map build (clean, terrain, normalize) per tile, and their products merged over
// the survey (docs/mapping.md, "Tiles and memory").
//
// ProcessTile works on one tile's points (core and overlap, in the working frame: the survey's
// coordinates minus the build's offset): voxel downsampling on the survey-wide voxel lattice, the
// statistical outlier removal with the tile's own statistics (mean and spread of the k-NN
// distances over the tile: in a survey whose density changes across the field, each tile is
// judged against its own density), the tile's DTM on the survey-wide DTM lattice, heights above it,
// and then keeps only what lies in the core: the band points (at h_ref and at each mesh level, these
// thinned to one per kLevelBandCellM cell), the points above the band (the canopy's top, thinned to
// the first point of each kTopCellM cell, for parts seen from one side: row_outline.hpp), the cleaned points' sample for the SVG and, if asked,
// the canopy points. The overlap (>= terrain.classification_radius_m) gives the
// core's cells the whole neighbourhood of their ground fit, so a core's products do not depend on
// where the tile boundaries fall, up to the outlier statistics.
//
// ProcessTiles makes two passes over a TiledCloud, one tile at a time. Pass 1 (CleanTile) cleans
// each core with only a kCleanMarginM margin (the outlier removal's k-NN queries, 60-70 % of the
// time, run on tiles.threads threads; cleaning the whole 3 m overlap would cost 30 % more on 40 m
// tiles) into a second tiled cloud; pass 2 (NormalizeTile) builds each tile's DTM from the cleaned
// points of its core and overlap, and keeps the core's products. Products are merged in tile
// order; the result does not depend on the number of threads. The survey's
// DTM is assembled from the tiles' grids: a cell comes from the tile whose core holds its centre,
// else (a cell at the survey's edge whose owner has no points) from the first tile whose grid
// covers it; cells of no tile are filled from their neighbours (FillFromNeighbours).
//
// Memory: one tile at a time, ~(24 + 80) bytes per point of the tile while it is processed (its
// points, the voxel keys, the float copy and FLANN's k-d tree), plus the merged products: 16 bytes
// per band point (h_ref and mesh levels) and top cell, the DTM (9 bytes per cell), the SVG sample (<= 20,000
// points) and, with keep_canopy, 24 bytes per canopy point.
#pragma once

#include "rowloc/mapping/map_build_config.hpp"
#include "rowloc/mapping/terrain_grid.hpp"
#include "rowloc/mapping/tiled_cloud.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <optional>
#include <string_view>
#include <vector>

namespace rowloc::mapping {

/// Called as work advances: the stage's name, units done, units in all.
using ProgressCallback = std::function<void(std::string_view stage, std::size_t done, std::size_t total)>;

struct TileProducts {
  std::size_t points_in = 0;         ///< the tile's points, overlap included
  std::size_t core_points_in = 0;    ///< of them, in the core
  std::size_t core_cleaned = 0;      ///< cleaned points in the core
  double voxel_seconds = 0.0;
  double outlier_seconds = 0.0;
  double terrain_seconds = 0.0;
  double normalize_seconds = 0.0;
  std::optional<TerrainGrid> terrain;          ///< the tile's DTM (core and overlap); nullopt if nothing was left
  std::vector<Eigen::Vector2d> band_m;         ///< the core's band points (x, y)
  std::vector<Eigen::Vector2d> sample_m;       ///< every sample_stride-th cleaned core point (x, y)
  std::vector<double> sample_height_m;         ///< their heights above the terrain
  std::vector<Eigen::Vector3d> canopy_m;       ///< keep_canopy: cleaned core points above the ground tolerance
  std::vector<std::vector<Eigen::Vector2d>> level_band_m;  ///< per mesh level (MeshLevelHeights): the core's band points, one per kLevelBandCellM cell
  std::vector<Eigen::Vector2d> top_m;          ///< the core's points above the band, the first of each kTopCellM cell (if outline.one_sided_max_width_m > 0)
};

struct TileJob {
  Rect2 core_m;                  ///< the tile's core in the working frame
  std::size_t sample_stride = 1; ///< keep every this-th cleaned core point for the SVG
  bool keep_canopy = false;
  int threads = 1;               ///< threads of the outlier removal's k-NN queries
};

/// The mesh levels' band points are kept as one centroid per square cell of this edge.
inline constexpr double kLevelBandCellM = 0.02;

/// Points within this distance of a core are cleaned with it (they hold its points' nearest
/// neighbours for the outlier statistic; the k-NN distances of a survey are centimetres).
inline constexpr double kCleanMarginM = 1.0;

/// Step 1 of one tile: its cleaned core points.
struct CleanedTile {
  std::vector<Eigen::Vector3d> core_points_m;  ///< cleaned points in the core
  std::size_t core_points_in = 0;
  std::size_t core_after_voxel = 0;
  double voxel_seconds = 0.0;
  double outlier_seconds = 0.0;
};

/// Step 1 on the points of core_m grown by kCleanMarginM (the others are dropped): voxel
/// centroids on the survey's lattice, then the outlier removal with the statistics of those
/// points; returns the cleaned points of the core. The config must be valid.
CleanedTile CleanTile(std::vector<Eigen::Vector3d> points_m, const Rect2& core_m, const MapBuildConfig& config,
                      int threads);

/// Steps 2-3 on one tile of cleaned points (core and overlap): the tile's DTM, then heights, band,
/// sample and canopy of the core's points.
TileProducts NormalizeTile(const std::vector<Eigen::Vector3d>& cleaned_m, const TileJob& job,
                           const MapBuildConfig& config);

/// Steps 1-3 on one tile's points alone (CleanTile on all of them, then NormalizeTile). The
/// config must be valid.
TileProducts ProcessTile(std::vector<Eigen::Vector3d> points_m, const TileJob& job, const MapBuildConfig& config);

/// Every tile's products, merged.
struct SurveyProducts {
  std::size_t tiles = 0;
  std::size_t largest_tile_points = 0;
  std::size_t stored_points = 0;     ///< points over all tiles, overlaps counted again
  std::size_t points_after_voxel = 0;
  std::size_t points_cleaned = 0;
  double voxel_seconds = 0.0;        ///< summed over tiles
  double outlier_seconds = 0.0;
  double terrain_seconds = 0.0;
  double normalize_seconds = 0.0;
  double wall_seconds = 0.0;         ///< of the whole tile loop
  int threads = 1;                   ///< threads of the outlier removal
  std::optional<TerrainGrid> terrain;  ///< the survey's DTM, working frame
  std::vector<Eigen::Vector2d> band_m;
  std::vector<Eigen::Vector2d> sample_m;
  std::vector<double> sample_height_m;
  std::vector<Eigen::Vector3d> canopy_m;
  std::vector<std::vector<Eigen::Vector2d>> level_band_m;  ///< per mesh level, as TileProducts
  std::vector<Eigen::Vector2d> top_m;                      ///< as TileProducts
};

/// ProcessTile over every tile of `cloud` (whose points are `offset_m` + working frame), releasing
/// each tile once processed. Throws std::invalid_argument for an empty cloud, an invalid config,
/// or a DTM of more than 10^8 cells; std::system_error if a spill file cannot be read.
SurveyProducts ProcessTiles(TiledCloud& cloud, const Eigen::Vector2d& offset_m, const MapBuildConfig& config,
                            bool keep_canopy, const ProgressCallback& progress = {});

}  // namespace rowloc::mapping
